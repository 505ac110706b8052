"""verify's output: concise by default (a header and a verdict per book, the failed checks and
their cells where cells differ), every check with -v, only the books that fail with -q; --json
one list of per-book objects with the same keys; likely causes in the book's order, runs down a
column as one range."""
from __future__ import annotations

import json
from pathlib import Path

import openpyxl
import pytest

from conftest import template
from linkbook.book import builder
from linkbook.apps import cli
from linkbook.base import sheets as layout

# these tests print the reports of three books that no test changes: each is verified once
pytestmark = pytest.mark.usefixtures("reports_once")


@pytest.fixture(scope="module")
def books(tmp_path_factory) -> dict:
    """A good four-bar (30° steps); the same with every xB cell of the sweep and one Motion
    cell that reads no xB cell made wrong; and a file that is no workbook."""
    folder = tmp_path_factory.mktemp("books")
    good = folder / "good.xlsx"
    builder.build_file(template("fourbar", step=30.0), good)
    wb = openpyxl.load_workbook(good)
    meta = layout.read_meta(wb)
    letter, (first, last) = meta["sweep"]["columns"]["xB"], meta["sweep"]["rows"]
    for r in range(first, last + 1):
        wb["Sweep"][f"{letter}{r}"].value += "+1"
    motion_row = meta["motion"]["rows"][0]
    wb["Motion"][f"B{motion_row}"].value += "+1"         # vxA: reads yA, not xB
    bad = folder / "bad.xlsx"
    wb.save(bad)
    junk = folder / "junk.xlsx"
    junk.write_text("not a workbook")
    causes = [f"Sweep!{letter}{first}:{letter}{last}", f"Motion!B{motion_row}"]
    return {"good": good, "bad": bad, "junk": junk, "causes": causes}


def _verify(capsys, *args) -> tuple[int, list[str], str]:
    code = cli.main(["verify", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out.strip().splitlines(), out.err


def test_a_passing_book_is_three_lines(books, capsys):
    """The header, the other input set judged and the verdict."""
    code, lines, err = _verify(capsys, books["good"])
    assert code == 0 and err == ""
    assert lines[0] == f"{books['good']}: fourbar, engine vector"
    assert lines[1].startswith("also judged at input set 2 (seed 1; ") and \
        lines[1].endswith(" cells compared"), lines
    assert len(lines) == 3 and lines[2].startswith("all agree: "), lines


def test_verbose_shows_every_check(books, capsys):
    code, lines, _ = _verify(capsys, books["good"], "-v")
    rows = [line for line in lines if line.endswith("  ok")]
    assert code == 0 and len(rows) > 50 and lines[-1].startswith("all agree: ")
    assert any(line.split()[:2] == ["Sweep", "theta13"] for line in rows)


def test_a_failing_book_shows_its_failed_checks_and_cells_only(books, capsys):
    code, lines, _ = _verify(capsys, books["bad"])
    assert code == 1
    assert not any(line.endswith("  ok") for line in lines), lines
    failed = [line for line in lines if line.endswith("DIFFER")]
    assert any(line.split()[:2] == ["Sweep", "xB"] for line in failed), lines
    assert any(line.startswith(f"  {books['causes'][1]}: expected") for line in lines)
    assert lines[-1].startswith(f"DISAGREES: ") and \
        f"likely cause {', '.join(books['causes'])};" in lines[-1], lines[-1]


def test_quiet_prints_only_what_fails(books, capsys):
    code, lines, err = _verify(capsys, books["good"], "-q")
    assert code == 0 and lines == [] and err == ""
    code, lines, err = _verify(capsys, books["good"], books["bad"], books["junk"], "-q")
    assert code == 2 and str(books["good"]) not in "\n".join(lines)
    assert lines[0] == f"{books['bad']}: fourbar, engine vector"
    assert lines[-1] == "3 books: 1 agree, 1 disagree, 1 cannot be verified"
    assert err.strip().splitlines() == [f"linkbook: error: {books['junk']}: not an .xlsx "
                                        "workbook (not a zip file)"]


def test_json_is_one_list_of_objects_with_the_same_keys(books, capsys):
    code, lines, _ = _verify(capsys, books["good"], "--json")
    one = json.loads("\n".join(lines))
    assert code == 0 and isinstance(one, list) and len(one) == 1 and one[0]["status"] == 0
    code, lines, err = _verify(capsys, books["good"], books["bad"], books["junk"], "--json")
    good, bad, junk = json.loads("\n".join(lines))
    assert code == 2 and set(good) == set(bad) == set(junk)
    assert [good["status"], bad["status"], junk["status"]] == [0, 1, 2]
    assert good["error"] is None and bad["error"] is None
    assert junk["error"] == f"{books['junk']}: not an .xlsx workbook (not a zip file)"
    assert junk["ok"] is False and junk["checks"] == [] and junk["book"] == str(books["junk"])
    assert good["seed"] == 1 and [s["set"] for s in good["input_sets"]] == [1, 2]
    assert junk["input_sets"] == []
    assert "junk.xlsx" in err


def test_likely_causes_are_ranges_in_the_books_order(books, capsys):
    """Sweep comes before Motion in the book (not in the alphabet), and the sweep's rows run
    5, 6, ..., 17 (not 10, 11, ..., 17, 5, ...): the column is one range."""
    code, lines, _ = _verify(capsys, books["bad"], "--json")
    [report] = json.loads("\n".join(lines))
    assert code == 1 and report["likely_causes"] == books["causes"]
