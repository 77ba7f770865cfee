"""Paper 002: its claims, named filters, scenarios and results page."""
