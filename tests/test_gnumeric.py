"""Gnumeric as a second real spreadsheet: `verify --engine gnumeric` recalculates a copy with
`ssconvert --recalc` and judges it by the rules the LibreOffice engine is judged by.

Tests that need ssconvert are skipped when it is missing (conftest's `needs`), except under CI
(CI set), where a missing Gnumeric is a failure: .ci/run installs it.
"""
from __future__ import annotations

import json
import re
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest
from conftest import HANG_GUARD_S, examples, passes_or_names_another_assembly
from openpyxl import Workbook

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT / "src") not in sys.path:        # conftest does this too; kept for --noconftest
    sys.path.insert(0, str(ROOT / "src"))

from linkbook.book import builder
from linkbook.engine import office
from linkbook.language import templates
from linkbook.check import verifier  # noqa: E402
from linkbook.apps.cli import main  # noqa: E402

BUNDLED = sorted(p.stem for p in (ROOT / "templates").glob("*.toml"))
NON_GRASHOF = ("a1=100", "a2=60", "a3=50", "a4=40")      # cannot turn fully: #N/A rows
# What Gnumeric 1.12 says on loading a bundled book, each an application difference that the
# README describes: Excel's own form of a print area of several ranges, and of print titles
# with both rows and columns ('Sweep'!$3:$4,'Sweep'!$A:$A), which Gnumeric cannot hold in a
# name; the footer of a different first page (Gnumeric reads only the odd header and footer);
# and an assertion inside Gnumeric's cell rendering, reached once it has loaded the charts.
KNOWN_WARNINGS = (
    re.compile(r"At [A-Z]+\d+: '('[^']+'!\$[A-Z]*\$?\d*(:\$[A-Z]*\$?\d*)?,?)+' Multiple "
               r"expressions are not supported in this context"),
    re.compile(r"Unexpected element 'firstFooter' in state : "),
    re.compile(r"\tworksheet -> headerFooter"),
    re.compile(r"\(ssconvert:\d+\): Pango-CRITICAL \*\*: [\d:.]+: pango_attr_list_filter: "
               r"assertion 'list != NULL' failed"),
    # the drawing's joint names: data labels showing their series' name, which Gnumeric
    # does not read
    re.compile(r"Unexpected element 'showSerName' in state : "),
    re.compile(r"\tchartSpace -> chart -> plotArea -> scatterChart -> ser -> dLbls"),
)

def _book(name: str, folder: Path, sets=()) -> Path:
    path = folder / f"{name}.xlsx"
    t = templates.with_overrides(templates.load(name), list(sets), None, None)
    builder.build_file(t, path)
    return path


# ---------------------------------------------------------------- without Gnumeric
def test_missing_ssconvert_says_how_to_install(monkeypatch, tmp_path):
    monkeypatch.setattr(office.shutil, "which", lambda name: None)
    assert office.ssconvert_path() is None
    (tmp_path / "a.xlsx").write_bytes(b"PK")
    with pytest.raises(office.OfficeUnavailable, match="apt-get install .*gnumeric"):
        office.recalculate(tmp_path / "a.xlsx", tmp_path, "gnumeric")


def test_verify_without_ssconvert_is_one_line(monkeypatch, tmp_path, capsys):
    book = _book("fourbar", tmp_path)
    monkeypatch.setattr(office.shutil, "which", lambda name: None)
    assert main(["verify", str(book), "--engine", "gnumeric"]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1, err
    assert err.startswith(f"linkbook: error: {book}: Gnumeric is needed for this (the "
                          "`ssconvert` command was not found)")


def test_silent_ssconvert_failure_is_an_error(monkeypatch, tmp_path):
    """ssconvert, like soffice, can exit 0 without writing the file: the missing output must
    raise, with the last line it printed."""
    fake = tmp_path / "ssconvert"
    fake.write_text("#!/bin/sh\necho 'Unexpected element' >&2\necho 'no can do' >&2\nexit 0\n")
    fake.chmod(0o755)
    monkeypatch.setattr(office, "ssconvert_path", lambda: str(fake))
    book = tmp_path / "b.xlsx"
    Workbook().save(book)
    with pytest.raises(office.OfficeFailed, match=r"^Gnumeric could not convert b.xlsx to "
                                                  r"\.xlsx \(exit 0\): no can do$"):
        office.recalculate(book, tmp_path / "out", "gnumeric")


def test_an_unknown_application_is_refused(tmp_path):
    with pytest.raises(ValueError, match="one of libreoffice, gnumeric"):
        office.recalculate(tmp_path / "a.xlsx", tmp_path, "excel")


# ---------------------------------------------------------------- with Gnumeric
@pytest.mark.gnumeric
def test_errors_as_gnumeric_computes_them(needs, tmp_path):
    """Gnumeric writes its errors with Excel's codes, and where LibreOffice differs from Excel
    (SQRT(-1), ATAN2(0, 0)) Gnumeric gives Excel's answer."""
    needs("gnumeric")
    wb = Workbook()
    formulas = ["=NA()", "=1/0", "=ACOS(2)", '="a"+1', '="abc"', "=1/3", "=NOSUCH()",
                "=ATAN2(0,0)", "=SQRT(-1)", '=IF(1,"",1)', "=1=1"]
    for i, f in enumerate(formulas, start=1):
        wb.active[f"A{i}"] = f
    wb.save(tmp_path / "e.xlsx")
    got = office.recalculated_values(tmp_path / "e.xlsx", "gnumeric")
    v = [got.get(("Sheet", f"A{i}")) for i in range(1, len(formulas) + 1)]
    assert [office.error_code(x) for x in v[:4]] == ["#N/A", "#DIV/0!", "#NUM!", "#VALUE!"]
    assert isinstance(v[0], office.CellError)
    assert v[4] == "abc" and not office.is_error(v[4])
    assert v[5] == 1 / 3
    assert office.error_code(v[6]) == "#NAME?"
    assert office.error_code(v[7]) == "#DIV/0!"      # LibreOffice: 0
    assert office.error_code(v[8]) == "#NUM!"        # LibreOffice: #VALUE!
    assert v[9] == "" and v[10] is True


@pytest.mark.gnumeric
def test_stale_cached_values_are_recalculated(needs, tmp_path):
    """A wrong cached value and no fullCalcOnLoad: --recalc must compute it again."""
    needs("gnumeric")
    from test_office import stale_book
    assert office.recalculated_values(stale_book(tmp_path), "gnumeric")[("Sheet", "B1")] == 6.0


@pytest.mark.gnumeric
@pytest.mark.parametrize("case", ["default", "non-grashof", "boom"])
def test_gnumeric_computes_the_sweep_and_motion_as_the_reference(needs, case, tmp_path):
    """The sheets that use no function Gnumeric lacks: every formula cell of the sweep table
    and of the motion sheet, judged by verify's rules, and the sweep columns against the
    reference directly."""
    needs("gnumeric")
    from test_office import _sweep_against_reference
    name, sets = {"default": ("fourbar", ()), "non-grashof": ("fourbar", NON_GRASHOF),
                  "boom": ("boom-cylinder", ())}[case]
    b, _ = builder.make(templates.with_overrides(templates.load(name), list(sets), None, None))
    path = tmp_path / f"{name}.xlsx"
    b.workbook.save(path)
    values = office.recalculated_values(path, "gnumeric")
    worst, na_rows = _sweep_against_reference(b, values)
    assert worst <= 1e-9
    assert (na_rows > 0) == (case == "non-grashof")
    checks = verifier.check_book(b.workbook, b.record, values, office.is_error, office.error_code,
                                 relative=True)
    tables = {b.meta["sweep"]["sheet"], "Motion"}
    judged = [k for c in checks for k in c.judged if k[0] in tables]
    bad = [f"{c.block}/{c.name}: {m.sheet}!{m.cell} expected {m.expected!r}, Gnumeric "
           f"{m.got!r}" for c in checks for m in c.mismatches if m.sheet in tables]
    assert not bad, "\n".join(bad[:8])
    assert len(judged) > 1000


@pytest.mark.gnumeric
@pytest.mark.parametrize("name", BUNDLED)
def test_gnumeric_recalculates_every_bundled_book_like_the_reference(needs, name, bundled_books,
                                                                     capsys):
    """Every formula cell of every bundled book, recalculated by Gnumeric, agrees with the
    reference (1e-9 relative, as LibreOffice)."""
    needs("gnumeric")
    path = bundled_books[name]
    status = main(["verify", str(path), "--engine", "gnumeric", "--json"])
    [report] = json.loads(capsys.readouterr().out)
    assert report["engine"] == "gnumeric" and report["status"] == status
    assert report["formula_cells"] == report["cells"] > 0 and not report["unjudged"]
    assert status == 0, report["likely_causes"][:6]


@pytest.mark.gnumeric
@pytest.mark.parametrize("name", BUNDLED)
def test_gnumeric_reads_every_bundled_book_and_its_charts(needs, name, bundled_books, tmp_path):
    """Gnumeric loads each book with no warning but the known ones, and keeps every chart."""
    needs("gnumeric")
    path = bundled_books[name]
    out = tmp_path / "gnumeric.xlsx"
    run = subprocess.run([office.ssconvert_path(), str(path), str(out)],
                         capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert run.returncode == 0 and out.is_file(), run.stderr
    unknown = [line for line in (run.stderr + run.stdout).splitlines()
               if line.strip() and not any(w.fullmatch(line) for w in KNOWN_WARNINGS)]
    assert not unknown, unknown
    assert _charts(out) == _charts(path) > 0


def _charts(path: Path) -> int:
    with zipfile.ZipFile(path) as z:
        return sum(1 for n in z.namelist() if re.fullmatch(r"xl/charts/chart\d+\.xml", n))


# The same books in other length units: every header, number format and the --unit conversion of
# the lengths, recalculated by Gnumeric and judged as above.
UNIT_VARIANTS = [("fourbar", "in"), ("jansen", "m"), ("boom-cylinder", "cm"), ("pump", "ft")]


@pytest.mark.gnumeric
@pytest.mark.parametrize("name,unit", UNIT_VARIANTS, ids=[f"{n}-{u}" for n, u in UNIT_VARIANTS])
def test_gnumeric_recalculates_unit_variants_like_the_reference(needs, name, unit, tmp_path):
    needs("gnumeric")
    path = tmp_path / f"{name}-{unit}.xlsx"
    builder.build_file(templates.with_unit(templates.load(name), unit), path)
    report = verifier.verify(path, "gnumeric")
    assert report.status == 0, [f"{m.sheet}!{m.cell}: {m.expected!r} vs {m.got!r}"
                                for c in report.checks for m in c.mismatches][:6]
    assert report.formula_cells == report.cells > 0


GNUMERIC_EXAMPLES = examples(2)


@pytest.mark.gnumeric
@pytest.mark.parametrize("family", BUNDLED)
def test_gnumeric_recalculates_random_dimensions_like_the_reference(needs, family, tmp_path):
    """Random dimensions of every bundled mechanism (test_properties' draws: crossed branches,
    non-Grashof linkages, loops that close over part of the sweep), recalculated by Gnumeric."""
    needs("gnumeric")
    from hypothesis import HealthCheck, given, settings
    from test_properties import dimensions, with_values
    base = templates.load(family)

    @settings(max_examples=GNUMERIC_EXAMPLES, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(dimensions(base))
    def check(values):
        path = tmp_path / "random.xlsx"
        builder.build_file(with_values(base, values), path)
        report = verifier.verify(path, "gnumeric")
        bad = [f"{m.sheet}!{m.cell}: {m.expected!r} vs {m.got!r}"
               for c in report.checks for m in c.mismatches]
        assert passes_or_names_another_assembly(report), (values, bad[:6])

    check()
