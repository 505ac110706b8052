"""The engine's errors: a workbook it cannot evaluate, and why."""


class EngineError(Exception):
    """The engine cannot evaluate this workbook."""


class UnsupportedFormulaError(EngineError):
    """A formula uses something outside the engine's documented limits."""


class CircularReferenceError(EngineError):
    """Formula cells read each other in a cycle."""
