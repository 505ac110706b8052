"""linkbook: planar mechanisms as living Excel workbooks (live formulas, charts, verification).

The Python API is these two calls (the command line does the same)::

    import linkbook

    path = linkbook.build("fourbar", "fourbar.xlsx", sets=["a2=45"], step=1)
    report = linkbook.verify(path)
    report.status        # 0 every formula cell agrees, 1 a cell differs, 2 some cannot be judged
    report.differing, report.causes, report.cells, report.formula_cells, report.inputs

Bad input raises `linkbook.InputError` (build) or `linkbook.UnusableFile` (verify), each with a
one-line message naming the field or the cell.
"""
from __future__ import annotations

from pathlib import Path

__version__ = "0.1.0"
__all__ = ["build", "verify", "InputError", "UnusableFile", "__version__"]


def build(template: str | Path, output: str | Path | None = None, *, sets=(), step=None,
          branch: str | None = None, unit: str | None = None, values: bool = False) -> Path:
    """Build one workbook: `template` a bundled name ("fourbar") or a .toml file; `sets` like
    the command line's --set ("a2=45"); `step` the sweep step; `branch` "open" or "crossed";
    `unit` the length unit (mm, cm, m, in, ft; the template's lengths converted to it);
    `values` stores computed values too. Returns the path written (default: <name>.xlsx here).
    """
    from . import builder, templates
    t = templates.load(str(template))
    if unit is not None:
        t = templates.with_unit(t, unit)
    t = templates.with_overrides(t, list(sets), step, branch)
    path = Path(output) if output is not None else Path(f"{t.name}.xlsx")
    if path.suffix.lower() != ".xlsx":
        raise templates.InputError("output", f"must name an .xlsx file (got {str(path)!r})")
    builder.build_file(t, path, values)
    return path


def verify(path: str | Path, engine: str = "vector"):
    """Every formula cell of the workbook at `path` against the independent reference; the
    Report (verifier.Report). `engine`: "vector" (default), "formulas", "libreoffice" or
    "gnumeric"."""
    from .verifier import verify as run
    return run(Path(path), engine)


def __getattr__(name: str):
    # the error types, without importing the whole package for `linkbook --version`
    if name == "InputError":
        from .templates import InputError
        return InputError
    if name == "UnusableFile":
        from .verifier import UnusableFile
        return UnusableFile
    raise AttributeError(f"module 'linkbook' has no attribute {name!r}")
