"""Paper 003: its claims, named filters, scenarios and results page."""
