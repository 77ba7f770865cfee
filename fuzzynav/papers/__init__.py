"""One folder per source paper: its claims, named filters, scenarios and results page.

A paper folder ``fuzzynav/papers/paperNNN/`` holds everything specific to that paper; the
generic house (``nav``, ``fuzzy``, ``filters``, ``sim``, ``tuning``) knows nothing of it.
"""
