"""linkbook: planar mechanisms as living Excel workbooks (live formulas, charts, verification).

The Python API is these three calls (the command line does the same)::

    import linkbook

    path = linkbook.build("fourbar", "fourbar.xlsx", sets=["a2=45"], step=1)
    report = linkbook.verify(path)
    report.status        # 0 every formula cell agrees, 1 a cell differs, 2 some cannot be judged
    report.differing, report.causes, report.cells, report.formula_cells, report.inputs
    data = linkbook.tables(path)     # {"Forces": {"T12 [N·m]": array([...]), ...}, ...}

Bad input to build raises `linkbook.InputError` (a one-line message naming the argument: `sets`,
`step`, `output`, ...), a file system that refuses the write `linkbook.CannotWrite` (an OSError).
verify never raises for the book it is given: one it cannot verify at all (not a workbook,
damaged, not linkbook's) gives a report of status 2 whose `error` is the one-line reason.
tables raises `linkbook.UnusableFile` (one line) for a book it cannot read.
"""
from __future__ import annotations

from pathlib import Path

from .base import __version__
__all__ = ["build", "verify", "tables", "InputError", "UnusableFile", "CannotWrite", "__version__"]


def build(template: str | Path, output: str | Path | None = None, *, sets=(), step=None,
          branch: str | None = None, unit: str | None = None, values: bool = False) -> Path:
    """Build one workbook: `template` a bundled name ("fourbar") or a .toml file; `sets` a list
    like the command line's --set (["a2=45"]); `step` the sweep step; `branch` "open" or
    "crossed"; `unit` the length unit (mm, cm, m, in, ft; the template's lengths converted to
    it); `values` stores computed values too. Returns the path written (default: <name>.xlsx
    here); `output`'s folder must exist. Raises InputError or CannotWrite with one line.
    """
    from .book.builder import build_template
    from .language import templates
    if isinstance(sets, str):
        raise templates.InputError("sets", f'must be a list of KEY=VALUE texts, such as '
                                           f'["a2=45"] (got the text {sets!r})')
    return build_template(template, output, sets=sets, step=step, branch=branch, unit=unit,
                          values=values, names=templates.ARGUMENTS)[0]


def verify(path: str | Path, engine: str = "vector", seed: int | None = None):
    """Every formula cell of the workbook at `path` against the independent reference; the
    Report (verifier.Report). `engine`: "vector" (default), "formulas", "libreoffice" or
    "gnumeric". With the vector engine the formulas are judged at another input set too,
    drawn from `seed` (None: the default seed; report.input_sets, report.seed).
    A book that cannot be verified at all gives a Report of status 2 with the reason in
    `error` (the line the command prints), so that a status is always there to act on."""
    from .check.verifier import report_of
    return report_of(path, engine, seed)


def tables(path: str | Path) -> dict:
    """Every table sheet of the book at `path` (Sweep, Motion, Forces, Grid, Stroke sweep: those
    it has) as {sheet: {header: numpy array of floats}}: each column under its header as the
    book prints it ("T12 [N·m]"), NaN where the book shows #N/A (or a text). The numbers are
    computed by linkbook's engine from the book's own formulas, so an edited book gives its
    edited numbers; they are the numbers `linkbook export` writes. Raises UnusableFile (one
    line) for a book it cannot read."""
    from .apps.export import arrays
    from .apps.info import open_book, read_record
    return read_record(open_book(Path(path)), arrays)


def __dir__() -> list[str]:
    # the error types are loaded on first use (__getattr__) but belong to the API all along
    return sorted(set(globals()) | set(__all__))


def __getattr__(name: str):
    # the error types, without importing the whole package for `linkbook --version`
    if name == "InputError":
        from .language.templates import InputError
        return InputError
    if name == "UnusableFile":
        from .check.verifier import UnusableFile
        return UnusableFile
    if name == "CannotWrite":
        from .base.files import CannotWrite
        return CannotWrite
    raise AttributeError(f"module 'linkbook' has no attribute {name!r}")
