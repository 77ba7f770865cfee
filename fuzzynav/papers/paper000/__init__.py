"""Paper 000: its claims, named filters, scenarios and results page."""
