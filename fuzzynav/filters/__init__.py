"""fuzzynav.filters"""
