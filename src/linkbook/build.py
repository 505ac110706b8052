"""From a checked template to a saved workbook: lay out, evaluate once, chart, write atomically."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

from . import charts, engine, workbook
from .templates import Template


def make(t: Template) -> tuple[workbook.Built, dict]:
    """The workbook and the value of every cell (the fast engine; used for chart scales)."""
    built = workbook.build(t)
    values = engine.evaluate(built.workbook)
    charts.add_charts(built, t, built.model, values)
    return built, values


def write_atomic(path: Path, write: Callable[[Path], None]) -> None:
    """Let `write` fill a temporary file beside the target, then rename it into place: an
    existing file is never left half-written, whatever happens before the rename."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(Path(tmp))
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def build_file(t: Template, path: Path, with_values: bool = False) -> workbook.Built:
    built, values = make(t)

    def write(tmp: Path) -> None:
        built.workbook.save(tmp)
        if with_values:
            from .cached import add_cached_values
            add_cached_values(tmp, tmp, values)

    write_atomic(path, write)
    return built
