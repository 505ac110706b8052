"""linkbook: planar mechanisms as living Excel workbooks (live formulas, charts, verification)."""
__version__ = "0.1.0"
