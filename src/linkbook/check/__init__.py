"""The check: the independent reference (reference/, forces.py), which shares nothing with the
writer, and the judge that compares every formula cell of a book with it (verifier)."""
