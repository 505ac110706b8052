"""`linkbook export`: a book's tables as CSV, each field the engine's value of the book's cell
and the value openpyxl reads stored in a --values book; text guarded against formula injection.
`linkbook.tables`: the same tables as arrays, equal to the CSVs."""
from __future__ import annotations

import csv
import math
import shutil
from pathlib import Path

import numpy as np
import openpyxl
import pytest

import linkbook
from conftest import built
from test_cli import run_in_process

from linkbook.engine import evaluator as engine
from linkbook.language.bundled import bundled
from linkbook.apps.export import tables, table_text
from linkbook.apps.info import Book
from linkbook.base.sheets import read_meta, write_meta_json
from linkbook.base.xlsx import column_letter


def _export(book, outdir) -> list:
    done = run_in_process("export", str(book), "-o", str(outdir))
    assert done.returncode == 0, done.stderr
    return sorted(outdir.iterdir())


def _rows(path) -> list[list[str]]:
    with open(path, encoding="utf-8-sig", newline="") as f:
        return list(csv.reader(f))


@pytest.fixture(scope="module")
def gappy_book(tmp_path_factory):
    """A four-bar whose loop cannot close over part of the sweep (#N/A there), values stored."""
    out = tmp_path_factory.mktemp("export") / "fourbar.xlsx"
    done = run_in_process("build", "fourbar", "--set", "a2=60", "--values", "-o",
                          str(out))
    assert done.returncode == 0, done.stderr
    return out


def _sheet_of(path) -> str:
    return {"Sweep": "Sweep", "Motion": "Motion", "Forces": "Forces"}[path.stem.split("-", 1)[1]]


def _compare(rows, cells, sheet, expected_of):
    """Every CSV field against the book's cell in the same place (rows: the CSV's book rows)."""
    compared = 0
    for line, row in zip(rows, cells):
        for col, text in enumerate(line, start=1):
            want = expected_of((sheet, f"{column_letter(col)}{row}"))
            if want is None:
                assert text == ""
            elif isinstance(want, (int, float)):
                assert float(text) == want      # repr: every bit survives
            else:
                assert text == str(want)        # a text, or an error as its code: #N/A
            compared += 1
    return compared


def test_round_trip_against_the_engine_and_the_stored_values(gappy_book, tmp_path):
    files = _export(gappy_book, tmp_path / "csv")
    assert [f.name for f in files] == ["fourbar-Forces.csv", "fourbar-Motion.csv",
                                       "fourbar-Sweep.csv"]
    computed = engine.evaluate_file(gappy_book)
    stored = openpyxl.load_workbook(gappy_book, data_only=True)
    meta = read_meta(stored)
    meta_rows = {"Sweep": (meta["sweep"]["rows"][0] - 1, *meta["sweep"]["rows"]),
                 "Motion": (meta["motion"]["current_row"] - 1, *meta["motion"]["rows"]),
                 "Forces": (meta["forces"]["current_row"] - 1, *meta["forces"]["rows"])}
    not_closing = 0
    for path in files:
        sheet = _sheet_of(path)
        head, first, last = meta_rows[sheet]
        rows = _rows(path)
        book_rows = [head, *range(first, last + 1)]
        assert len(rows) == len(book_rows)
        assert rows[0][0] == stored[sheet][f"A{head}"].value == "θ12 [deg]"
        assert _compare(rows, book_rows, sheet, computed.get) > 1000
        assert _compare(rows, book_rows, sheet,
                        lambda key: stored[key[0]][key[1]].value) > 1000
        not_closing += sum(line.count("#N/A") for line in rows)
    assert not_closing > 0      # the gaps came out as #N/A


def test_a_book_without_stored_values_exports_the_same_numbers(gappy_book, tmp_path):
    bare = tmp_path / "fourbar.xlsx"
    done = run_in_process("build", "fourbar", "--set", "a2=60", "-o", str(bare))
    assert done.returncode == 0, done.stderr
    assert openpyxl.load_workbook(bare, data_only=True)["Sweep"]["C5"].value is None
    with_values = _export(gappy_book, tmp_path / "a")
    without = _export(bare, tmp_path / "b")
    for one, other in zip(with_values, without):
        assert one.read_bytes() == other.read_bytes()


@pytest.mark.parametrize("text", ["=HYPERLINK(\"x\")", "+1", "-2", "@SUM(A1)", "\tx", "\rx"])
def test_text_read_as_a_formula_is_prefixed(coarse_fourbar, tmp_path, text):
    book = tmp_path / "fourbar.xlsx"
    wb = openpyxl.load_workbook(coarse_fourbar)     # the header is the point, not the rows
    cell = wb["Sweep"]["B4"]
    cell.value = text
    cell.data_type = "s"        # a text that starts with =, not a formula
    wb.save(book)
    files = _export(book, tmp_path / "csv")
    sweep = next(f for f in files if f.stem.endswith("Sweep"))
    header = _rows(sweep)[0]
    assert header[1] == "'" + text
    assert header[0] == "θ12 [deg]"       # an ordinary text is left as it is


def test_every_table_sheet_of_the_pump(tmp_path):
    """The grid's two header rows and its stroke row; the stroke sweep's header of s1 values
    (beside the sweep, its motion and, the pump having masses and a load, its forces)."""
    b, values = built("pump")
    book = Book("pump.xlsx", b.workbook, b.record, values)
    found = tables(book)
    assert [t.sheet for t in found] == ["Sweep", "Motion", "Forces", "Grid", "Stroke sweep"]
    grid = next(t for t in found if t.sheet == "Grid")
    lines = list(csv.reader(table_text(book, grid).splitlines()))
    ws = b.workbook["Grid"]
    assert lines[0][1] == ws["B4"].value and lines[1][0] == ws["A5"].value
    assert [float(x) for x in lines[1][1:]] == [ws.cell(5, c).value for c in range(2, 8)]
    assert lines[-1][0] == ws[f"A{b.meta['grid']['stroke_row']}"].value
    assert float(lines[-1][1]) == values[("Grid", f"B{b.meta['grid']['stroke_row']}")]
    stroke = next(t for t in found if t.sheet == "Stroke sweep")
    lines = list(csv.reader(table_text(book, stroke).splitlines()))
    assert [float(x) for x in lines[0][1:]] == [ws.cell(5, c).value for c in range(2, 8)]
    assert len(lines) == 1 + b.meta["stroke"]["rows"][1] - b.meta["stroke"]["rows"][0] + 1


def test_a_missing_book_is_one_line(tmp_path):
    done = run_in_process("export", "missing.xlsx", cwd=tmp_path)
    assert done.returncode == 2 and len(done.stderr.splitlines()) == 1
    assert "no such file" in done.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_record_that_does_not_match_the_book_is_one_line(bundled_books, tmp_path):
    """The build record without its sweep entry: named as verify names it, nothing written."""
    book = Path(shutil.copy(bundled_books["fourbar"], tmp_path / "fourbar.xlsx"))
    wb = openpyxl.load_workbook(book)
    meta = read_meta(wb)
    del meta["sweep"]
    write_meta_json(wb["linkbook"], meta)
    wb.save(book)
    for command in (("export", str(book), "-o", str(tmp_path / "csv")), ("info", str(book))):
        done = run_in_process(*command)
        assert done.returncode == 2 and done.stdout == ""
        assert len(done.stderr.splitlines()) == 1
        assert "the build record (sheet linkbook) does not match the workbook" in done.stderr
    assert not (tmp_path / "csv").exists()


def _csv_number(text: str) -> float:
    """A CSV field as the number it shows: NaN for #N/A, a text or an empty field."""
    try:
        return float(text)
    except ValueError:
        return math.nan


def _same_as_the_csvs(book, outdir, heads=None) -> int:
    """linkbook.tables(book) against `linkbook export`'s files: the sheets, each header (the
    CSV's last header row) and every number (NaN where the CSV has no number). How many NaN."""
    found = linkbook.tables(book)
    files = _export(book, outdir)
    assert sorted(path.name for path in files) == sorted(
        f"{book.stem}-{sheet.replace(' ', '-')}.csv" for sheet in found)
    nan = 0
    for sheet, columns in found.items():
        rows = _rows(outdir / f"{book.stem}-{sheet.replace(' ', '-')}.csv")
        head = (heads or {}).get(sheet, 1)
        assert list(columns) == rows[head - 1], sheet
        for i, (header, values) in enumerate(columns.items()):
            expected = np.array([_csv_number(row[i]) for row in rows[head:]])
            assert np.array_equal(values, expected, equal_nan=True), (sheet, header)
            nan += int(np.isnan(expected).sum())
    return nan


def test_tables_are_the_csvs_with_na_as_nan(gappy_book, tmp_path):
    assert _same_as_the_csvs(gappy_book, tmp_path / "csv") > 0
    found = linkbook.tables(gappy_book)
    computed = engine.evaluate_file(gappy_book)
    meta = read_meta(openpyxl.load_workbook(gappy_book))
    first, last = meta["forces"]["rows"]
    letter = meta["forces"]["columns"]["T12"]
    t12 = [computed[("Forces", f"{letter}{r}")] for r in range(first, last + 1)]
    assert any(engine.is_error(v) for v in t12)     # the book shows #N/A where the gap is
    assert np.array_equal(found["Forces"]["T12 [N·m]"],
                          [math.nan if engine.is_error(v) else v for v in t12], equal_nan=True)


def test_tables_give_an_edited_books_numbers(bundled_books, tmp_path):
    """a2 typed over in the saved book: the sweep's crank tip moves with it."""
    book = Path(shutil.copy(bundled_books["fourbar"], tmp_path / "fourbar.xlsx"))
    before = linkbook.tables(book)["Sweep"]
    wb = openpyxl.load_workbook(book)
    wb["Mechanism"]["C8"] = 2 * wb["Mechanism"]["C8"].value         # a2, the crank
    wb.save(book)
    after = linkbook.tables(book)["Sweep"]
    assert np.allclose(after["xA [mm]"], 2 * before["xA [mm]"], rtol=1e-12, atol=1e-9)
    assert np.ptp(after["xA [mm]"]) > 0


def test_tables_of_a_missing_book_raise_one_line(tmp_path):
    with pytest.raises(linkbook.UnusableFile, match="no such file"):
        linkbook.tables(tmp_path / "missing.xlsx")


@pytest.mark.slow       # every bundled template built, exported and read
@pytest.mark.parametrize("name", [path.stem for path in bundled()])
def test_tables_equal_the_csvs_of_every_bundled_book(name, tmp_path):
    book = linkbook.build(name, tmp_path / f"{name}.xlsx")
    _same_as_the_csvs(book, tmp_path / "csv", heads={"Grid": 2})
