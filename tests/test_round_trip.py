"""Books come back: a book saved by a real spreadsheet application is read, judged and exported
as the book linkbook wrote (issue 36).

Every bundled book is built, then saved as .xlsx
- by LibreOffice as a user's `soffice --convert-to xlsx` does (a fresh profile with the default
  settings: no recalculation forced), and through LibreOffice's own API after an edit of a length
  and a mass (tests/uno_edit.py, run by the Python that has Debian's python3-uno);
- by Gnumeric's `ssconvert --recalc`.
Each saved book must verify with exit 0 (every formula cell compared, the values the application
stored judged too), and info, export and animate must read it; an edit is followed (verify agrees
at the new inputs, info shows them); a formula changed after the save is caught. What each save
changes in the file is pinned at the end, as docs/applications.md describes it.
"""
from __future__ import annotations

import json
import subprocess
import tempfile
import zipfile
from pathlib import Path

import pytest

from conftest import HANG_GUARD_S, UNO_PYTHON, template
from linkbook.apps.cli import main
from linkbook.book import builder
from linkbook.check.verifier import report_of
from linkbook.engine import office

ROOT = Path(__file__).resolve().parents[1]
BUNDLED = sorted(p.stem for p in (ROOT / "templates").glob("*.toml"))
EDITOR = Path(__file__).with_name("uno_edit.py")
# An edit a user makes: one length and one mass (the new values keep every mechanism assembled
# where it was).
EDITS = {"fourbar": {"a2": 30.0, "m3": 0.9}, "slider-crank": {"a2": 45.0, "m3": 1.5},
         "pump": {"a2": 50.0, "m2": 0.2}, "toggle-press": {"a2": 18.0, "m2": 0.05}}

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def built(bundled_books) -> Path:
    """The folder of every bundled book (conftest's, built once for the run)."""
    [folder] = {p.parent for p in bundled_books.values()}
    return folder


@pytest.fixture(scope="module")
def saved_by_libreoffice(needs, built, tmp_path_factory) -> Path:
    """Every book through one `soffice --convert-to xlsx`, with a new profile of the default
    settings (the user's command; no recalculation forced on load)."""
    needs("libreoffice")
    out = tmp_path_factory.mktemp("libreoffice")
    with tempfile.TemporaryDirectory(prefix="linkbook-profile-") as profile:
        subprocess.run([office.soffice_path(), f"-env:UserInstallation={Path(profile).as_uri()}",
                        "--headless", "--norestore", "--convert-to", "xlsx", "--outdir",
                        str(out), *sorted(str(built / f"{name}.xlsx") for name in BUNDLED)],
                       check=True, stdin=subprocess.DEVNULL, capture_output=True,
                       timeout=2 * HANG_GUARD_S)
    return out


@pytest.fixture(scope="module")
def saved_by_gnumeric(needs, built, tmp_path_factory) -> Path:
    needs("gnumeric")
    out = tmp_path_factory.mktemp("gnumeric")
    for book in sorted(built / f"{name}.xlsx" for name in BUNDLED):
        subprocess.run([office.ssconvert_path(), "--recalc", str(book), str(out / book.name)],
                       check=True, stdin=subprocess.DEVNULL, capture_output=True,
                       timeout=HANG_GUARD_S)
    return out


@pytest.fixture(scope="module")
def edited_in_libreoffice(needs, built, tmp_path_factory) -> dict[str, tuple[Path, dict]]:
    """name -> (the book saved by LibreOffice's API after its EDITS were typed, the values
    LibreOffice shows in the edited cells)."""
    needs("libreoffice", "uno")
    from linkbook.check.reading import read_book
    out = tmp_path_factory.mktemp("edited")
    books = {}
    for name, edits in EDITS.items():
        _, record = read_book(built / f"{name}.xlsx")
        cells = {f"Mechanism!{record.inputs[s].cell}": v for s, v in edits.items()}
        shown = subprocess.run([UNO_PYTHON, str(EDITOR), str(built / f"{name}.xlsx"),
                                str(out / f"{name}.xlsx"), json.dumps(cells)], check=True,
                               capture_output=True, text=True, timeout=HANG_GUARD_S).stdout
        books[name] = (out / f"{name}.xlsx", json.loads(shown))
    return books


def _same_judgement(saved: Path, built: Path) -> None:
    """The saved book agrees, cell for cell as many as the book linkbook wrote, and the values
    the application stored with its formulas were judged too."""
    mine, theirs = report_of(built), report_of(saved)
    assert theirs.error is None, theirs.error
    assert theirs.status == 0, [(c.name, c.mismatches[:3]) for c in theirs.checks if not c.ok]
    assert theirs.formula_cells == mine.formula_cells and theirs.cells == mine.cells
    assert theirs.unjudged == [] and theirs.notes == []
    stored = [c for c in theirs.checks if c.block == "stored"]
    assert stored and stored[0].cells == mine.formula_cells, "the stored values were not judged"


def _reads(saved: Path, built: Path, tmp_path: Path, capsys) -> None:
    """info, export and animate read the saved book; export's tables are the built book's."""
    assert main(["info", str(saved)]) == 0
    assert main(["export", str(saved), "-o", str(tmp_path / "saved")]) == 0
    assert main(["export", str(built), "-o", str(tmp_path / "built")]) == 0
    mine = sorted(p.name for p in (tmp_path / "built").iterdir())
    assert mine == sorted(p.name for p in (tmp_path / "saved").iterdir())
    for csv in mine:
        assert (tmp_path / "saved" / csv).read_bytes() == (tmp_path / "built" / csv).read_bytes()
    from linkbook.check.reading import read_book
    wb, record = read_book(saved)
    first = wb[record.sweep.sheet][f"A{record.sweep.rows[0]}"].value     # the input's column
    assert main(["animate", str(saved), "-o", str(tmp_path / "frame.png"), "--at",
                 str(first)]) == 0
    assert (tmp_path / "frame.png").stat().st_size > 0
    said = capsys.readouterr()
    assert "Traceback" not in said.err and "warning" not in said.err, said.err


@pytest.mark.libreoffice
@pytest.mark.parametrize("name", BUNDLED)
def test_a_book_saved_by_libreoffice_verifies_and_reads(saved_by_libreoffice, built, name,
                                                        tmp_path, capsys):
    _same_judgement(saved_by_libreoffice / f"{name}.xlsx", built / f"{name}.xlsx")
    _reads(saved_by_libreoffice / f"{name}.xlsx", built / f"{name}.xlsx", tmp_path, capsys)


@pytest.mark.gnumeric
@pytest.mark.parametrize("name", BUNDLED)
def test_a_book_saved_by_gnumeric_verifies_and_reads(saved_by_gnumeric, built, name, tmp_path,
                                                     capsys):
    _same_judgement(saved_by_gnumeric / f"{name}.xlsx", built / f"{name}.xlsx")
    _reads(saved_by_gnumeric / f"{name}.xlsx", built / f"{name}.xlsx", tmp_path, capsys)


@pytest.mark.libreoffice
@pytest.mark.parametrize("name", sorted(EDITS))
def test_an_edit_saved_by_libreoffice_is_followed(edited_in_libreoffice, built, name, tmp_path,
                                                  capsys):
    """The inputs typed in LibreOffice are the ones verify judges at and info shows; the
    judgement is a fresh build's at those inputs (its cells judged as many)."""
    path, shown = edited_in_libreoffice[name]
    assert sorted(shown.values()) == sorted(EDITS[name].values())
    report = report_of(path)
    assert report.status == 0, [(c.name, c.mismatches[:3]) for c in report.checks if not c.ok]
    for symbol, value in EDITS[name].items():
        assert report.inputs[symbol] == value
    fresh = tmp_path / "fresh.xlsx"
    builder.build_file(template(name, [f"{s}={v}" for s, v in EDITS[name].items()]), fresh)
    assert report.cells == report_of(fresh).cells
    capsys.readouterr()
    assert main(["info", str(path), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    listed = {row["symbol"]: row["value"] for row in info["inputs"]}
    for symbol, value in EDITS[name].items():
        assert listed[symbol] == value


def _tampered(saved: Path, out: Path) -> tuple[Path, str]:
    """A copy of `saved` with one Sweep formula multiplied by 1.001 in its XML, as an edit
    after the save would leave it; and the cell."""
    from linkbook.check.reading import read_book
    wb, record = read_book(saved)
    column = record.sweep.columns["mu"] if "mu" in record.sweep.columns else \
        sorted(record.sweep.columns.values())[-1]
    cell = f"{column}{record.sweep.rows[0] + 3}"
    sheet_part = f"xl/worksheets/sheet{wb.sheetnames.index('Sweep') + 1}.xml"
    with zipfile.ZipFile(saved) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename == sheet_part:
                text = data.decode("utf-8")
                start = text.index(f'<c r="{cell}"')
                f_open = text.index("<f", start)
                f_body = text.index(">", f_open) + 1
                f_end = text.index("</f>", f_body)
                text = text[:f_body] + "(" + text[f_body:f_end] + ")*1.001" + text[f_end:]
                data = text.encode("utf-8")
            zout.writestr(info, data)
    return out, cell


@pytest.mark.libreoffice
@pytest.mark.gnumeric
@pytest.mark.parametrize("name", ["fourbar", "pump"])
def test_a_formula_changed_after_the_save_is_caught(saved_by_libreoffice, saved_by_gnumeric,
                                                    name, tmp_path):
    for folder in (saved_by_libreoffice, saved_by_gnumeric):
        path, cell = _tampered(folder / f"{name}.xlsx", tmp_path / f"{folder.name}.xlsx")
        report = report_of(path)
        assert report.status == 1
        assert ("Sweep", cell) in report.causes, sorted(report.causes)[:5]


# ---------------------------------------------------------------- what each save changes
def _parts(path: Path) -> set[str]:
    with zipfile.ZipFile(path) as z:
        return set(z.namelist())


def _hidden_sheets(path: Path) -> set[str]:
    import openpyxl
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        wb = openpyxl.load_workbook(path, read_only=True)
    try:
        return {ws.title for ws in wb.worksheets if ws.sheet_state != "visible"}
    finally:
        wb.close()


@pytest.mark.libreoffice
@pytest.mark.gnumeric
def test_what_each_save_changes(saved_by_libreoffice, saved_by_gnumeric, built):
    """What docs/applications.md says each save loses: neither keeps
    the form controls (spin button, scroll bar); Gnumeric shows the record sheet; both keep
    every chart and every formula."""
    book = "fourbar.xlsx"
    controls = {p for p in _parts(built / book) if p.startswith("xl/ctrlProps/")}
    assert controls
    for folder in (saved_by_libreoffice, saved_by_gnumeric):
        parts = _parts(folder / book)
        assert not parts & controls
        charts = [p for p in parts if p.startswith("xl/charts/chart")]
        assert len(charts) == len([p for p in _parts(built / book)
                                   if p.startswith("xl/charts/chart")])
    assert _hidden_sheets(built / book) == {"linkbook"}
    assert _hidden_sheets(saved_by_libreoffice / book) == {"linkbook"}
    assert _hidden_sheets(saved_by_gnumeric / book) == set()
