"""The engine's errors: a workbook it cannot evaluate, and why; and an application that cannot
recalculate one (office.py raises these; here so that catching them imports no subprocess)."""


class EngineError(Exception):
    """The engine cannot evaluate this workbook."""


class UnsupportedFormulaError(EngineError):
    """A formula uses something outside the engine's documented limits."""


class CircularReferenceError(EngineError):
    """Formula cells read each other in a cycle."""


class OfficeUnavailable(Exception):
    """soffice (or pdftoppm, for previews) is not installed."""


class OfficeFailed(Exception):
    """soffice ran but did not produce the file it was asked for (or timed out)."""
