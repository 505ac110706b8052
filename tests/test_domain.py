"""One domain for build and verify (linkbook.language.domain): what build accepts, its own verify accepts
and agrees with; what verify would refuse, or what would not fit the memory budget, build refuses
up front with one line naming the limit and the figure, and writes nothing."""
from __future__ import annotations

import time
import zipfile
from pathlib import Path

import openpyxl
import pytest

from conftest import ROOT, template
import linkbook
from linkbook.book import builder
from linkbook.language import domain
from linkbook.base import safety
from test_bad_input import _run  # the command run in a folder of its own

FOURBAR_TOML = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")




def refused(tmp_path: Path, capsys, args: list[str], *must_hold: str) -> None:
    before = sorted(p.name for p in tmp_path.iterdir())
    code, err = _run(tmp_path, ["build", *args, "-o", "out.xlsx"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and lines[0].startswith("linkbook: error: "), err
    for text in must_hold:
        assert text in lines[0], lines[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "a file was left behind"


def builds_and_verifies(tmp_path: Path, capsys, args: list[str]) -> None:
    code, err = _run(tmp_path, ["build", *args, "-o", "out.xlsx"], capsys)
    assert code == 0, err
    report = linkbook.verify(tmp_path / "out.xlsx")
    assert report.status == 0, [m for c in report.checks for m in c.mismatches][:5]


def mine(tmp_path: Path, old: str, new: str) -> str:
    assert old in FOURBAR_TOML
    (tmp_path / "mine.toml").write_text(FOURBAR_TOML.replace(old, new), encoding="utf-8")
    return "mine.toml"


# ---------------------------------------------------------------- lengths
def test_a_crank_a_million_times_its_frame_is_refused(tmp_path, capsys):
    """shaper r2 = 1e9 beside r1 = 60: rounding at 1e9 is beyond the bound at 60 (domain's
    docstring); build refused it not, and its verify then failed."""
    refused(tmp_path, capsys, ["shaper", "--set", "r2=1e9"], "r1", "r2 = 1e+09",
            "at most 1000 times apart")


def test_a_crank_a_thousand_times_its_frame_builds_and_verifies(tmp_path, capsys):
    builds_and_verifies(tmp_path, capsys, ["shaper", "--set", "r2=6e4"])


def test_a_ground_coordinate_beyond_the_range_is_refused(tmp_path, capsys):
    toml = mine(tmp_path, "A0 = [0, 0]", "A0 = [0, 1e30]")
    refused(tmp_path, capsys, [toml], "mine.toml: mechanism.ground.A0[1]", "1e+30")


def test_a_ground_coordinate_far_beyond_the_links_is_refused(tmp_path, capsys):
    toml = mine(tmp_path, "A0 = [0, 0]", "A0 = [0, 1e6]")
    refused(tmp_path, capsys, [toml], "a2", "mechanism.ground.A0[1] = 1e+06",
            "at most 1000 times apart")


def test_a_ground_coordinate_inside_the_domain_builds_and_verifies(tmp_path, capsys):
    """...and counts in the mechanism's size S, which scales the bounds: the lengths 70, 35,
    62.3, 56, 126.6 and 84.1 mm and the coordinates written as numbers."""
    builds_and_verifies(tmp_path, capsys, [mine(tmp_path, "A0 = [0, 0]", "A0 = [-2e4, 3e4]")])
    size = linkbook.verify(tmp_path / "out.xlsx").size
    assert size == pytest.approx(70 + 35 + 62.3 + 56 + 126.6 + 84.1 + 2e4 + 3e4, rel=1e-12)


# ---------------------------------------------------------------- the input's range
@pytest.mark.parametrize("old,new,field,figure", [
    ("position = 60", "position = 1e15", "sweep.position", "1e+15"),
    ("stop = 360", "stop = 3600.0001", "sweep.stop", "3600.0001"),
    ("stop = 360", "stop = 360000", "sweep.stop", "360000"),
    ("start = 0", "start = -3601", "sweep.start", "-3601"),
])
def test_a_sweep_beyond_the_input_range_is_refused(tmp_path, capsys, old, new, field, figure):
    refused(tmp_path, capsys, [mine(tmp_path, old, new)], f"mine.toml: {field}: {figure}",
            "±3600°")


def test_a_sweep_at_the_input_range_builds_and_verifies(tmp_path, capsys):
    toml = mine(tmp_path, "start = 0\nstop = 360\nstep = 5\nposition = 60",
                "start = -3600\nstop = 3600\nstep = 20\nposition = -3600")
    builds_and_verifies(tmp_path, capsys, [toml])


# ---------------------------------------------------------------- sizes
PUMP_1000 = ",".join(f"{20 + i * 0.05:g}" for i in range(1000))


@pytest.mark.parametrize("args,limit", [
    (["fourbar", "--step", "0.001"], "verify reads at most 512 MiB"),
    (["fourbar", "--step", "0.000344"], "verify reads at most 512 MiB"),
    (["tk-fourbar", "--step", "0.005"], "the budget is 4 GiB"),
    (["pump", "--set", f"s1={PUMP_1000}"], "verify reads at most 512 MiB"),
], ids=["step 0.001", "step 0.000344", "step 0.005", "pump, 1000 adjustments"])
def test_a_book_too_big_for_verify_or_memory_is_refused_up_front(tmp_path, capsys, args, limit):
    started = time.process_time()       # CPU time: another process's load does not count
    refused(tmp_path, capsys, args, "book size", limit)
    assert time.process_time() - started < 30


def test_a_pump_with_excels_most_columns_is_refused_up_front():
    values = ",".join(f"{20 + i * 0.001:.3f}" for i in range(16_383))
    t = template("pump", [f"s1={values}"])
    with pytest.raises(domain.InputError, match="book size: .* verify reads at most 512 MiB"):
        builder.make(t)


@pytest.mark.parametrize("name,sets,step", [
    ("fourbar", (), 0.5), ("pump", (f"s1={','.join(str(20 + i) for i in range(20))}",), None),
    ("jansen", (), 1.0)])
@pytest.mark.slow        # three large books built
def test_the_size_estimate_is_within_a_quarter_of_the_book(tmp_path, name, sets, step):
    """The up-front estimate against the written file's own inflated size (its zip directory)
    and formula cells."""
    t = template(name, sets, step)
    cells, xml = builder.book_size(t)
    path = tmp_path / "book.xlsx"
    builder.build_file(t, path)
    with zipfile.ZipFile(path) as z:
        real = sum(i.file_size for i in z.infolist())
    report = linkbook.verify(path)
    assert abs(cells - report.formula_cells) <= 0.01 * report.formula_cells + 100
    assert real * 0.75 <= xml <= real * 1.25 + builder.OTHER_PARTS


def test_a_written_book_verify_would_refuse_is_not_placed(tmp_path, monkeypatch):
    """The estimate may miss: the written file is checked as verify checks it before it takes
    the place of anything."""
    path = tmp_path / "fourbar.xlsx"
    path.write_bytes(b"the earlier file")
    monkeypatch.setattr(safety, "MAX_UNCOMPRESSED", 100_000)
    with pytest.raises(domain.InputError, match="book size: verify would refuse the book: "
                                                "would inflate to"):
        builder.build_file(template("fourbar"), path)
    assert path.read_bytes() == b"the earlier file"
    assert [p.name for p in tmp_path.iterdir()] == ["fourbar.xlsx"]


# ---------------------------------------------------------------- text in an input cell
@pytest.mark.parametrize("name,text", [
    ("a_2", "1_0"), ("a_2", "１０"), ("m_3", "١٠"), ("m_3", "10"), ("Branch", "1")],
    ids=["underscore", "full-width", "Arabic-Indic", "plain digits", "branch"])
def test_text_in_an_input_cell_is_refused_with_the_cell_named(tmp_path, capsys, name, text):
    """Text where a number belongs is #VALUE! in LibreOffice and Gnumeric, whatever its digits;
    Python's float() would read every one of these as a number."""
    code, err = _run(tmp_path, ["build", "fourbar", "-o", "fb.xlsx"], capsys)
    assert code == 0, err
    wb = openpyxl.load_workbook(tmp_path / "fb.xlsx")
    cell = wb.defined_names[name].attr_text.split("!")[1].replace("$", "")
    wb["Mechanism"][cell].value = text          # openpyxl stores a str as text
    wb.save(tmp_path / "fb.xlsx")
    code, err = _run(tmp_path, ["verify", "fb.xlsx"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert f"(cell {cell}): must be a number, not text (got {text!r})" in lines[0], lines[0]


def test_a_formula_in_an_input_cell_is_named_as_a_formula(tmp_path, capsys):
    """=50 typed where a2 belongs: an input is a number, and the message says what is there."""
    code, err = _run(tmp_path, ["build", "fourbar", "-o", "fb.xlsx"], capsys)
    assert code == 0, err
    wb = openpyxl.load_workbook(tmp_path / "fb.xlsx")
    cell = wb.defined_names["a_2"].attr_text.split("!")[1].replace("$", "")
    wb["Mechanism"][cell].value = "=50"
    wb.save(tmp_path / "fb.xlsx")
    code, err = _run(tmp_path, ["verify", "fb.xlsx"], capsys)
    lines = err.strip().splitlines()
    assert code == 2 and len(lines) == 1, err
    assert f"input a2 (cell {cell}): holds a formula (=50); an input must be a number typed in " \
        "its cell" in lines[0], lines[0]
