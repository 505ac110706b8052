"""From a checked template to a saved workbook: lay out, evaluate once, chart, write atomically."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

from . import charts, engine, workbook
from .templates import Template


def make(t: Template) -> tuple[workbook.Built, dict]:
    """The workbook and the value of every cell (the fast engine; used for chart scales)."""
    built = workbook.build(t)
    values = engine.evaluate(built.workbook)
    charts.add_charts(built, t, built.model, values)
    return built, values


def save_atomic(wb, path: Path) -> None:
    """Write beside the target, then rename: an existing file is never left half-written."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        wb.save(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def build_file(t: Template, path: Path) -> workbook.Built:
    built, _ = make(t)
    save_atomic(built.workbook, path)
    return built
