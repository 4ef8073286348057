"""springmodel."""
