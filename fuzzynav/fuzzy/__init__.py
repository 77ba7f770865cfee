"""fuzzynav.fuzzy"""
