"""fuzzynav.tuning"""
