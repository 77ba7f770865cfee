"""Paper 001: its claims, named filters, scenarios and results page."""
