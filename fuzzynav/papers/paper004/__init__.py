"""Paper 004: its claims, named filters, scenarios and results page."""
