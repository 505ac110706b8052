"""A book whose formulas name another workbook (an external link) is refused where every
reader of a book starts (safety.check_zip), with one line naming the cell: no engine, no
application and no command opens the file the book names outside itself."""
from __future__ import annotations

import subprocess
import sys
import zipfile
from pathlib import Path

import openpyxl
import pytest

from conftest import ROOT
from linkbook.apps.cli import main

MAIN_NS = "http://schemas.openxmlformats.org/spreadsheetml/2006/main"
REL_NS = "http://schemas.openxmlformats.org/officeDocument/2006/relationships"
INPUT_CELL = '<c r="N8" s="8"><f>I17</f>'        # Mechanism!N8 = I17, the current x of B


@pytest.fixture(scope="module")
def fourbar(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("fourbar") / "fourbar.xlsx"
    assert main(["build", "fourbar", "-o", str(path)]) == 0
    return path


def linked_book(book: Path, out: Path, target: str, formula: str = "[1]Sheet1!A1") -> Path:
    """The book with Mechanism!N8 reading Sheet1!A1 of the workbook at `target`, as Excel
    writes an external link: the formula's [1], an externalLink part (with the value Excel
    last saw, 35) and its relationship to the file, TargetMode="External"."""
    link = (f'<externalLink xmlns="{MAIN_NS}" xmlns:r="{REL_NS}"><externalBook r:id="rId1">'
            '<sheetNames><sheetName val="Sheet1"/></sheetNames><sheetDataSet>'
            '<sheetData sheetId="0"><row r="1"><cell r="A1"><v>35</v></cell></row></sheetData>'
            '</sheetDataSet></externalBook></externalLink>')
    link_rels = ('<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/'
                 f'relationships"><Relationship Id="rId1" Type="{REL_NS}/externalLinkPath" '
                 f'Target="{target}" TargetMode="External"/></Relationships>')
    edits = {
        "xl/worksheets/sheet1.xml": (INPUT_CELL, INPUT_CELL.replace("I17", formula)),
        "xl/workbook.xml": ("</sheets>", "</sheets><externalReferences><externalReference "
                            f'xmlns:r="{REL_NS}" r:id="rIdX1"/></externalReferences>'),
        "xl/_rels/workbook.xml.rels": ("</Relationships>", f'<Relationship Id="rIdX1" Type="'
                                       f'{REL_NS}/externalLink" Target="externalLinks/'
                                       'externalLink1.xml"/></Relationships>'),
        "[Content_Types].xml": ("</Types>", '<Override PartName="/xl/externalLinks/'
                                'externalLink1.xml" ContentType="application/vnd.openxmlformats-'
                                'officedocument.spreadsheetml.externalLink+xml"/></Types>'),
    }
    with zipfile.ZipFile(book) as src, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename in edits:
                old, new = edits[info.filename]
                assert old.encode() in data
                data = data.replace(old.encode(), new.encode(), 1)
            dst.writestr(info, data)
        dst.writestr("xl/externalLinks/externalLink1.xml", link)
        dst.writestr("xl/externalLinks/_rels/externalLink1.xml.rels", link_rels)
    return out


def other_book(path: Path, value: float) -> Path:
    wb = openpyxl.Workbook()
    wb.active.title = "Sheet1"
    wb.active["A1"] = value
    wb.save(path)
    return path


def current_x_of_b(fourbar: Path) -> float:
    """The value Mechanism!I17 (and so N8) holds, as the book stores it."""
    return openpyxl.load_workbook(fourbar, data_only=True)["Mechanism"]["I17"].value


COMMANDS = [["verify"], ["verify", "--engine", "formulas"], ["verify", "--engine", "libreoffice"],
            ["verify", "--engine", "gnumeric"], ["info"], ["export"], ["animate"]]


@pytest.mark.parametrize("command", COMMANDS, ids=[" ".join(c) for c in COMMANDS])
@pytest.mark.parametrize("exists", [False, True], ids=["no such file", "a file that agrees"])
def test_a_book_with_an_external_link_is_refused(tmp_path, fourbar, capsys, command, exists):
    """The linked file, where it exists, holds the very value the cell should have: a reader
    that opened it would agree (as `--engine formulas` did) instead of refusing."""
    target = tmp_path / "other.xlsx"
    if exists:
        other_book(target, current_x_of_b(fourbar))
    book = linked_book(fourbar, tmp_path / "linked.xlsx", target.as_uri())
    before = sorted(p.name for p in tmp_path.iterdir())
    capsys.readouterr()
    code = main([command[0], str(book), *command[1:]])
    out = capsys.readouterr()
    lines = out.err.strip().splitlines()
    assert code == 2, out
    assert lines == [f"linkbook: error: {book}: cell Mechanism!N8 has an external reference "
                     "('[1]Sheet1!A1'); linkbook reads no file but the book"], out
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "a file was written"


def test_a_link_no_formula_uses_is_refused_naming_the_part(tmp_path, fourbar, capsys):
    """The link's part alone (a name or nothing reads it): named, with the file it names."""
    book = linked_book(fourbar, tmp_path / "linked.xlsx", "file:///no/such/other.xlsx",
                       formula="I17")
    capsys.readouterr()
    assert main(["verify", str(book)]) == 2
    assert capsys.readouterr().err.strip() == (
        f"linkbook: error: {book}: part xl/externalLinks/externalLink1.xml is an external "
        "reference to 'file:///no/such/other.xlsx'; linkbook reads no file but the book")


def test_a_bracket_in_a_formula_string_is_no_external_reference(tmp_path, fourbar, capsys):
    path = tmp_path / "text.xlsx"
    with zipfile.ZipFile(fourbar) as src, zipfile.ZipFile(path, "w") as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "xl/worksheets/sheet1.xml":
                data = data.replace(INPUT_CELL.encode(),
                                    INPUT_CELL.replace("I17", 'IF(1,I17,"[1]Sheet1!A1")')
                                    .encode(), 1)
            dst.writestr(info, data)
    capsys.readouterr()
    assert main(["verify", str(path)]) == 0, capsys.readouterr()


@pytest.mark.parametrize("engine", ["formulas", "libreoffice"])
def test_no_engine_opens_the_linked_file(needs, tmp_path, fourbar, engine):
    """Seen from the operating system: no process of the command opens the named file."""
    needs("strace", *(["libreoffice"] if engine == "libreoffice" else []))
    target = other_book(tmp_path / "other.xlsx", current_x_of_b(fourbar))
    book = linked_book(fourbar, tmp_path / "linked.xlsx", target.as_uri())
    log = tmp_path / "strace.log"
    run = subprocess.run(["strace", "-f", "-e", "trace=openat,open", "-o", str(log),
                          sys.executable, "-m", "linkbook.apps.cli", "verify", str(book),
                          "--engine", engine], capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT / "src"), "PATH": "/usr/bin:/bin"})
    assert run.returncode == 2 and "external reference" in run.stderr, run.stderr
    opened = [line for line in log.read_text().splitlines() if "other.xlsx" in line]
    assert opened == [], opened
