"""`linkbook info`: a book's numbers at the terminal, each one equal to the independent
reference's (check/reference/), also after the book is edited; a template summarised in memory;
the Forces sheet's summary, each number its cell's."""
from __future__ import annotations

import json
import shutil

import numpy as np
import openpyxl
import pytest

from conftest import template
from test_cli import run_in_process

from linkbook.check import reference as generic

DEG_TOL = 1e-9      # verify's bound for an angle


def _book(tmp_path, *sets) -> tuple:
    out = tmp_path / "fourbar.xlsx"
    done = run_in_process("build", "fourbar", *(a for s in sets for a in ("--set", s)),
                          "-o", str(out))
    assert done.returncode == 0, done.stderr
    return out, template("fourbar", sets)


def _info(target, cwd=None) -> dict:
    done = run_in_process("info", str(target), "--json", cwd=cwd)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def _reference(t) -> dict:
    return generic.solve(t.mechanism.description, t.values(), np.array(t.sweep.angles()))


def _range(data: dict, section: str, symbol: str) -> dict:
    return next(r for r in data[section] if r["what"].split()[-1] == symbol)


def _same_angle(a: float, b: float) -> bool:
    return abs((a - b + 180.0) % 360.0 - 180.0) <= DEG_TOL


def test_fourbar_numbers_are_the_reference_numbers(bundled_books):
    book, t = bundled_books["fourbar"], template("fourbar")
    data = _info(book)
    ref = _reference(t)
    loop = generic.fourbar_loops(t.mechanism.description, t.values())[0]
    assert [r["grashof"] for r in data["fourbar_loops"]] == [generic.grashof_class(*loop)]

    theta14 = np.unwrap(ref["theta14"])     # one continuous curve: its range is the swing
    shown = _range(data, "angles", "θ14")
    assert shown["unit"] == "deg"
    assert _same_angle(shown["min"], np.degrees(theta14.min()))
    assert _same_angle(shown["max"], np.degrees(theta14.max()))
    assert abs((shown["max"] - shown["min"]) - np.degrees(np.ptp(theta14))) <= DEG_TOL

    mu = _range(data, "transmission_angles", "μ")
    assert abs(mu["min"] - np.degrees(np.nanmin(ref["mu"]))) <= DEG_TOL
    assert abs(mu["max"] - np.degrees(np.nanmax(ref["mu"]))) <= DEG_TOL
    assert data["gaps"] == []

    printed = run_in_process("info", str(book)).stdout.splitlines()
    line = next(x for x in printed if x.split()[:1] == ["θ14"])
    assert line.split()[1:] == [f"{shown['min']:.6g}", "…", f"{shown['max']:.6g}", "deg"]
    line = next(x for x in printed if x.strip().startswith("transmission angle μ"))
    assert line.split()[-4:] == [f"{mu['min']:.6g}", "…", f"{mu['max']:.6g}", "deg"]
    assert f"four-bar loop A0 A B B0: {generic.grashof_class(*loop)}" in printed[
        printed.index("Four-bar loops") + 1]

    omega = next(p for p in data["peaks"] if p["what"] == "ω14")
    assert omega["unit"] == "rad/s"
    ref_omega = np.abs(ref["omega_theta14"])
    assert abs(omega["peak"] - ref_omega.max()) <= 1e-9 * ref_omega.max()
    assert omega["at"] == t.sweep.angles()[int(np.argmax(ref_omega))]


def _gaps_of(angles, assembled) -> list[dict]:
    """The reference's runs of input angles where the loop does not close."""
    gaps, start = [], None
    for i, ok in enumerate(assembled):
        if not ok and start is None:
            start = angles[i]
        if not ok and (i + 1 == len(angles) or assembled[i + 1]):
            gaps.append({"from": start, "to": angles[i]})
            start = None
    return gaps


def test_an_edited_book_reports_its_edited_values(bundled_books, tmp_path):
    """a2 typed over in the saved book (as in Excel): the loop turns non-Grashof and leaves
    gaps; info reports those, the reference's, not the numbers the book was built with."""
    book = tmp_path / "fourbar.xlsx"
    wb = openpyxl.load_workbook(bundled_books["fourbar"])
    wb["Mechanism"]["C8"] = 60          # a2, the crank
    wb.save(book)
    data = _info(book)
    edited = template("fourbar", ["a2=60"])
    ref = _reference(edited)
    loop = generic.fourbar_loops(edited.mechanism.description, edited.values())[0]
    assert data["fourbar_loops"][0]["grashof"] == generic.grashof_class(*loop) \
        == "non-Grashof: triple rocker"
    a2 = next(r for r in data["inputs"] if r["symbol"] == "a2")
    assert (a2["value"], a2["unit"]) == (60, "mm")
    expected = _gaps_of(edited.sweep.angles(), ref["assembled"])
    assert expected and data["gaps"] == expected
    assert data["not_closing"] == int((~ref["assembled"]).sum())


def test_a_template_is_summarised_in_memory_as_its_book_is(bundled_books, tmp_path):
    from_book = _info(bundled_books["fourbar"])
    empty = tmp_path / "here"
    empty.mkdir()
    from_template = _info("fourbar", cwd=empty)
    assert list(empty.iterdir()) == []      # nothing written
    for key in ("fourbar_loops", "angles", "transmission_angles", "gaps", "peaks", "inputs"):
        assert from_template[key] == from_book[key]


def test_the_text_fits_80_columns_and_names_units(tmp_path):
    book, _ = _book(tmp_path, "a2=60")
    done = run_in_process("info", str(book))
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert max(map(len, lines)) < 80
    text = done.stdout
    assert "non-Grashof: triple rocker" in text and "from " in text and "rad/s" in text
    assert any(line.split()[:1] == ["θ14"] and line.rstrip().endswith("deg") for line in lines)


def test_a_long_label_is_wrapped_not_cut(tmp_path):
    """The slider-crank's branch label is longer than the line has room for: all of it shows."""
    done = run_in_process("info", "slider-crank", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert max(map(len, done.stdout.splitlines())) < 80
    label = next(p.label for p in template("slider-crank").parameters if p.symbol == "branch")
    assert " ".join(done.stdout.split()).count(" ".join(label.split())) == 1


@pytest.mark.parametrize("target, says", [("missing.xlsx", "no such file"),
                                          ("no-such-template", "no-such-template")])
def test_bad_input_is_one_line(tmp_path, target, says):
    done = run_in_process("info", target, cwd=tmp_path)
    assert done.returncode == 2
    assert done.stdout == ""
    assert len(done.stderr.splitlines()) == 1 and says in done.stderr
    assert done.stderr.startswith("linkbook: error: ")


FORCE_SUMMARY = {
    "effort_mean": "N·m", "effort_rms": "N·m", "effort_largest": "N·m",
    "effort_largest_at": "deg", "effort_smallest": "N·m", "effort_smallest_at": "deg",
    "energy_fluctuation": "J", "speed_fluctuation": "-", "flywheel": "kg·m²"}


def _force_cells(book) -> dict:
    """{key: the engine's value} of every cell of the Forces sheet's summary, where the build
    record says it is."""
    from linkbook.base.sheets import read_meta
    from linkbook.engine import evaluator as engine
    values = engine.evaluate_file(book)
    cells = read_meta(openpyxl.load_workbook(book))["forces"]["summary"]
    return {key: values[("Forces", c["cell"])] for key, c in cells.items()
            if not key.startswith(("mean_line", "polar_square"))}


@pytest.mark.parametrize("name, pins", [("fourbar", ["F12", "F23", "F34", "F14"]),
                                        ("slider-crank", ["F12", "F23", "F34", "F14"])])
def test_the_force_summary_is_the_forces_sheets(bundled_books, name, pins):
    """Every number of the Forces summary (mean effort, RMS, extremes and where, each pin's
    peak, energy fluctuation, Cs, flywheel inertia), as the engine computes its cell, with its
    unit, in --json and in the text."""
    book = bundled_books[name]
    summary = _info(book)["force_summary"]
    shown = {r["key"]: r for r in summary}
    cells = _force_cells(book)
    expected_units = {**FORCE_SUMMARY, **{f"peak_{pin}": "N" for pin in pins}}
    assert set(shown) == set(cells) == set(expected_units)
    for key, value in cells.items():
        assert isinstance(value, float) and shown[key]["value"] == value, key
        assert shown[key]["unit"] == expected_units[key], key
    assert shown["flywheel"]["what"] == "flywheel inertia ΔE / (Cs·ω²)"
    text = run_in_process("info", str(book)).stdout.splitlines()
    block = text[text.index("Forces: summary over the θ12 sweep") + 1:]
    assert len(block) == len(cells)
    for line, r in zip(block, summary):
        assert line.split()[-2:] == [f"{r['value']:.6g}", r["unit"]], line
        assert line.strip().startswith(r["what"])


def test_the_force_summary_follows_an_edited_cs(bundled_books, tmp_path):
    """Cs typed over in the book (an input of the Forces sheet): twice Cs, half the flywheel."""
    book = tmp_path / "slider-crank.xlsx"
    shutil.copy(bundled_books["slider-crank"], book)
    before = {r["key"]: r["value"] for r in _info(book)["force_summary"]}
    cell = _info_cell(book, "speed_fluctuation")
    wb = openpyxl.load_workbook(book)
    wb["Forces"][cell] = 2 * before["speed_fluctuation"]
    wb.save(book)
    after = {r["key"]: r["value"] for r in _info(book)["force_summary"]}
    assert after["speed_fluctuation"] == 2 * before["speed_fluctuation"]
    assert after["flywheel"] == pytest.approx(before["flywheel"] / 2, rel=1e-12)


def _info_cell(book, key: str) -> str:
    from linkbook.base.sheets import read_meta
    return read_meta(openpyxl.load_workbook(book))["forces"]["summary"][key]["cell"]


def _info_of_toml(tmp_path, name: str, edit) -> tuple[dict, str]:
    """info (--json and the text) of bundled template `name` as edit(its text) makes it."""
    from conftest import ROOT
    text = (ROOT / "templates" / f"{name}.toml").read_text(encoding="utf-8")
    edited = edit(text)
    assert edited != text
    (tmp_path / "mine.toml").write_text(edited, encoding="utf-8")
    return (_info("mine.toml", cwd=tmp_path),
            run_in_process("info", "mine.toml", cwd=tmp_path).stdout)


def test_the_rate_of_a_symbol_in_bars_is_written_d_dt(tmp_path):
    """A distance named |P1P4|: its rates d|P1P4|/dt and d²|P1P4|/dt², no dot combined onto a
    bar (||̇P1P4||); a symbol that starts with a letter keeps its dots (ė, ë)."""
    data, text = _info_of_toml(tmp_path, "tk-fourbar", lambda t: t.replace(
        'key = "d"\n', 'key = "d"\nsymbol = "|P1P4|"\n', 1))
    rates = [p["what"] for p in data["peaks"]]
    assert {"d|P1P4|/dt", "d²|P1P4|/dt²", "e\u0307", "e\u0308"} <= set(rates), rates
    for mark in ("\u0307", "\u0308"):
        assert not any(c in "|()[]" for c in
                       (text[i - 1] for i, ch in enumerate(text) if ch == mark)), text


def test_an_angle_output_is_shown_once(tmp_path):
    """output = theta14: its range under the output's label, not again as an angle."""
    data, text = _info_of_toml(tmp_path, "fourbar", lambda t: t.replace(
        "[mechanism]\n", '[mechanism]\noutput = "theta14"\n', 1))
    assert [r["what"] for r in data["output"]] == ["θ14 (rocker, angle of B0→B)"]
    assert [r["what"] for r in data["angles"]] == ["θ13"]
    assert sum(line.split()[:1] == ["θ14"] for line in text.splitlines()) == 1
