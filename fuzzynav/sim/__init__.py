"""fuzzynav.sim"""
