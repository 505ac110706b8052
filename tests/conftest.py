"""Shared test helpers: building templates in memory and the published acceptance data."""
from __future__ import annotations

import sys
import tomllib
from functools import lru_cache
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.language import templates  # noqa: E402
from linkbook.check.verifier import check_book  # noqa: E402


PUBLISHED = ROOT / "tests" / "data" / "published.toml"


@lru_cache(maxsize=None)
def published() -> dict:
    """tests/data/published.toml: the numbers the sources printed (each entry names its source)."""
    return tomllib.loads(PUBLISHED.read_text(encoding="utf-8"))


def template(name: str, sets=(), step=None, branch=None) -> templates.Template:
    return templates.with_overrides(templates.load(name), list(sets), step, branch)


@lru_cache(maxsize=None)
def built(name: str, sets: tuple = (), step=None, branch=None):
    """(Built, values) of a template with overrides, evaluated by the vector engine."""
    return builder.make(template(name, sets, step, branch))


def formula_cells(wb) -> set[tuple[str, str]]:
    return {(ws.title, c.coordinate) for ws in wb.worksheets for row in ws.iter_rows()
            for c in row if isinstance(c.value, str) and c.value.startswith("=")}


def checks_of(b, values):
    return check_book(b.workbook, b.record, values, engine.is_error, engine.error_code)


def value_at(b, values, key: str, angle: float, sheet: str = "Sweep"):
    """The sweep value of column `key` on the row whose input angle is `angle`."""
    ws = b.workbook[sheet]
    first, last = b.meta["sweep"]["rows"]
    for r in range(first, last + 1):
        if abs(ws[f"A{r}"].value - angle) < 1e-9:
            return values[(sheet, f"{b.meta['sweep']['columns'][key]}{r}")]
    raise KeyError(angle)


def pytest_terminal_summary(terminalreporter):
    """Report how many random examples ran per family, and how many had unassembled rows."""
    try:
        from test_properties import TALLY
    except ImportError:
        return
    if not TALLY:
        return
    terminalreporter.section("property tests")
    for family in sorted({f for f, _ in TALLY}):
        terminalreporter.write_line(
            f"{family:24} {TALLY[(family, 'examples')]:5d} examples, "
            f"{TALLY[(family, 'with rows that cannot close')]:5d} with rows that cannot close"
            + (f", {TALLY[(family, 'tasks with no design')]} tasks with no design"
               if (family, "tasks with no design") in TALLY else ""))
