"""A formula of an angle reads it in the turn the book shows it in (issue 39): an angle column is
determined only up to whole turns, and each book shows it in a window of its own choosing (the
four-bar's ϕ in [0, 2π), where ATAN2's cut would fall on its samples). A load or an `expression`
of the angle itself (`T*theta14`, `IF(theta14 > 1.5, …)`) means what it means with the angle as
shown: the reference evaluates it so, and the book agrees."""
from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from linkbook.book import builder
from linkbook.check.verifier import verify
from linkbook.language import templates

ROOT = Path(__file__).resolve().parents[1]
FOURBAR = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")


def _fourbar_with(load: str | None = None, expression: str | None = None) -> templates.Template:
    data = tomllib.loads(FOURBAR)
    if load is not None:
        data["mechanism"]["loads"][0]["torque"] = load
    if expression is not None:
        data["mechanism"]["steps"].append({"type": "expression", "key": "q", "symbol": "q",
                                           "label": "a formula of the rocker's angle",
                                           "unit": "-", "formula": expression})
        data["mechanism"]["columns"].append("q")
    return templates.from_data("fourbar-turns", data)


@pytest.mark.parametrize("load", ["T4*theta14", "IF(theta14 > 2.5, -T4, T4)",
                                  "T4*(theta14 - 2)*phi"])
def test_a_load_of_an_angle_agrees(tmp_path, load):
    """Before, 589 cells differed on the rows from 185° to 360°, where the reference read ϕ (and
    θ14 = ϕ − ψ) a turn below the book's."""
    path = tmp_path / "book.xlsx"
    builder.build_file(_fourbar_with(load=load), path)
    report = verify(path)
    assert report.status == 0, [(c.name, c.mismatches[:2]) for c in report.checks if not c.ok]


def test_an_expression_of_an_angle_agrees(tmp_path):
    path = tmp_path / "book.xlsx"
    builder.build_file(_fourbar_with(expression="theta14*10 + phi"), path)
    report = verify(path)
    assert report.status == 0, [(c.name, c.mismatches[:2]) for c in report.checks if not c.ok]


def test_a_wrong_load_of_an_angle_is_still_caught(tmp_path):
    """The turn is the book's; the formula is still the reference's: a load whose book formula
    reads another angle differs."""
    import openpyxl
    path = tmp_path / "book.xlsx"
    builder.build_file(_fourbar_with(load="T4*theta14"), path)
    wb = openpyxl.load_workbook(path)
    found = 0
    for ws in wb.worksheets:
        for row in ws.iter_rows():
            for c in row:
                if isinstance(c.value, str) and c.value.startswith("=") and "T_4*" in c.value:
                    c.value = c.value.replace("T_4*", "T_4*1.001*")
                    found += 1
    assert found
    wb.save(path)
    assert verify(path).status == 1
