"""`linkbook verify`, the vector engine against ExcelModel, and `build --values`."""
from __future__ import annotations

import dataclasses
import json
import math
import shutil
import zipfile
from pathlib import Path

import numpy as np
import openpyxl
import pytest

from conftest import formula_cells, template
from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.language import templates
from linkbook.apps.cli import main
from linkbook.base.sheets import read_meta

BUNDLED = sorted(p.stem for p in templates.bundled())


def _small(name: str) -> templates.Template:
    """A bundled template with fewer rows (a 30-unit step: every formula shape is still there)
    and, under the pump grid, a coarser fine sweep and two of its values (two columns: the
    grid's formulas and how they reach across), so that ExcelModel (about 75 ms per
    1,000-character grid formula, a few ms per cell) finishes in seconds."""
    t = templates.load(name)
    t = dataclasses.replace(t, sweep=dataclasses.replace(t.sweep, step=max(t.sweep.step, 30.0)))
    return dataclasses.replace(t, stroke_step=20.0, grid_values=t.grid_values[:2]) \
        if t.mechanism.grid else t


def _same(a, b) -> bool:
    if engine.is_error(a) or engine.is_error(b):
        return engine.error_code(a) == engine.error_code(b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12)
    return a == b


@pytest.mark.slow
@pytest.mark.parametrize("name", BUNDLED)
def test_vector_engine_equals_excelmodel_on_every_cell(name, tmp_path):
    path = tmp_path / f"{name}.xlsx"
    builder.build_file(_small(name), path)
    wb = openpyxl.load_workbook(path)
    fast = engine.evaluate(wb)
    slow = engine.evaluate_formulas_model(path)
    cells = formula_cells(wb)
    assert cells
    errors = sum(engine.is_error(fast[c]) for c in cells)
    differ = [(c, fast[c], slow.get(c)) for c in sorted(cells) if not _same(fast[c], slow.get(c))]
    assert not differ, differ[:5]
    if name == "fourbar":
        assert errors == 0      # Example 2 assembles at every angle


@pytest.mark.slow        # the per-cell engine over a whole book
def test_errors_come_through_cell_by_cell(tmp_path):
    """A non-Grashof four-bar: ExcelModel and the vector engine give #N/A on the same cells."""
    t = template("fourbar", ("a1=100", "a2=60", "a3=50", "a4=40"), 10)
    path = tmp_path / "ng.xlsx"
    builder.build_file(t, path)
    wb = openpyxl.load_workbook(path)
    fast, slow = engine.evaluate(wb), engine.evaluate_formulas_model(path)
    na = [c for c in formula_cells(wb) if engine.error_code(fast[c]) == "#N/A"]
    assert len(na) > 50
    assert all(engine.error_code(slow[c]) == "#N/A" for c in na)


def _verify(*args, capsys):
    code = main(["verify", *map(str, args)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_verify_passes_a_fresh_book(bundled_books, capsys):
    path = bundled_books["fourbar"]
    code, out, _ = _verify(path, "-v", capsys=capsys)
    assert code == 0, out
    assert "all agree" in out and "theta13" in out


def test_verify_finds_a_tampered_formula_and_names_the_cell(bundled_books, tmp_path, capsys):
    path = tmp_path / "fb.xlsx"
    wb = openpyxl.load_workbook(bundled_books["fourbar"])
    ws = wb["Sweep"]
    cell = ws["H20"]                       # one formula cell in the middle of the table
    assert cell.value.startswith("=")
    cell.value = cell.value + "*1.001"
    wb.save(path)
    code, out, _ = _verify(path, capsys=capsys)
    assert code == 1
    assert "Sweep!H20" in out and "DISAGREES" in out
    code, out, _ = _verify(path, "--json", capsys=capsys)
    [report] = json.loads(out)
    assert code == 1 and not report["ok"]
    bad = [m for c in report["checks"] for m in c["mismatches"]]
    assert {(m["sheet"], m["cell"]) for m in bad} >= {("Sweep", "H20")}


def test_verify_uses_inputs_edited_like_a_user_would(bundled_books, tmp_path, capsys):
    path = tmp_path / "fb.xlsx"
    wb = openpyxl.load_workbook(bundled_books["fourbar"])
    where = wb.defined_names["a_2"].attr_text.split("!")[1].replace("$", "")
    wb["Mechanism"][where].value = 41.5
    branch = wb.defined_names["Branch"].attr_text.split("!")[1].replace("$", "")
    wb["Mechanism"][branch].value = -1
    wb["Mechanism"]["I7"].value = 123.0        # the current-position angle
    wb.save(path)
    code, out, _ = _verify(path, capsys=capsys)
    assert code == 0, out


def test_verify_with_the_formulas_engine(tmp_path, capsys):
    path = tmp_path / "sc.xlsx"
    assert main(["build", "slider-crank", "--step", "30", "-o", str(path)]) == 0
    code, out, _ = _verify(path, "--engine", "formulas", capsys=capsys)
    assert code == 0, out


def _zip_bomb(path: Path) -> None:
    """A sheet that inflates to 600 MiB of zeros (beyond safety.MAX_UNCOMPRESSED), deflated at
    the quickest level and written a chunk at a time: the same archive to verify, made in a
    fraction of the time and memory."""
    chunk = b"\0" * (8 * 1024 * 1024)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as zf:
        zf.writestr("[Content_Types].xml", "<Types/>")
        with zf.open("xl/worksheets/sheet1.xml", "w") as sheet:
            for _ in range(600 * 1024 * 1024 // len(chunk)):
                sheet.write(chunk)


def _entities(path: Path, source: Path) -> None:
    with zipfile.ZipFile(source) as zin, zipfile.ZipFile(path, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item)
            if item.filename == "xl/workbook.xml":
                body = data.split(b"?>", 1)[1] if data.startswith(b"<?xml") else data
                data = (b'<?xml version="1.0"?><!DOCTYPE lol [<!ENTITY lol "lol">'
                        b'<!ENTITY lol2 "&lol;&lol;&lol;">]>' + body)
            zout.writestr(item, data)


@pytest.mark.parametrize("kind", ["missing", "not a zip", "truncated", "zip bomb",
                                  "xml entities", "not linkbook"])
def test_verify_refuses_unusable_files_with_exit_2(bundled_books, tmp_path, capsys, kind):
    good = bundled_books["slider-crank"]
    bad = tmp_path / "bad.xlsx"
    if kind == "not a zip":
        bad.write_text("theta12,s14\n0,1\n")
    elif kind == "truncated":
        bad.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    elif kind == "zip bomb":
        _zip_bomb(bad)
    elif kind == "xml entities":
        _entities(bad, good)
    elif kind == "not linkbook":
        wb = openpyxl.Workbook()
        wb.active["A1"] = "=1+1"
        wb.save(bad)
    code, out, err = _verify(bad, capsys=capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith("linkbook: error: ")


def test_build_with_values_caches_every_formula(tmp_path):
    path = tmp_path / "ng.xlsx"
    assert main(["build", "fourbar", "--set", "a1=100", "--set", "a2=60", "--set", "a3=50",
                 "--set", "a4=40", "--values", "-o", str(path)]) == 0
    with_formulas = openpyxl.load_workbook(path)
    cached = openpyxl.load_workbook(path, data_only=True)
    cells = formula_cells(with_formulas)
    numbers = na = 0
    for sheet, ref in cells:
        v = cached[sheet][ref].value
        if v == "#N/A":
            na += 1
        else:
            assert isinstance(v, (int, float, str)) and v is not None, (sheet, ref, v)
            numbers += isinstance(v, (int, float))
    assert na > 0 and numbers > na
    # The same file read normally still has its formulas, names and charts.
    assert with_formulas["Sweep"]["C5"].value.startswith("=")
    assert "a_2" in with_formulas.defined_names
    assert with_formulas["Charts"]._charts and with_formulas["Mechanism"]._charts


def test_build_refuses_a_sweep_beyond_excels_rows_before_any_work(tmp_path, capsys):
    code = main(["build", "fourbar", "--step", "0.0003", "-o", str(tmp_path / "x.xlsx")])
    assert code == 2 and "1,048,576" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_build_refuses_a_grid_beyond_excels_columns(tmp_path, capsys):
    many = ",".join(str(i) for i in range(16_400))
    code = main(["build", "pump", "--set", f"s1={many}", "-o", str(tmp_path / "x.xlsx")])
    assert code == 2 and "16,384" in capsys.readouterr().err


@pytest.mark.libreoffice
@pytest.mark.parametrize("name", BUNDLED)
def test_libreoffice_recalculates_every_bundled_book_like_the_reference(
        name, bundled_books, recalculated_by_libreoffice, monkeypatch):
    """The real application: a full recalculation in LibreOffice, every formula cell against the
    reference (1e-9 relative: LibreOffice stores 15 significant digits)."""
    from linkbook.check.verifier import verify
    from linkbook.engine import office
    path, asked = bundled_books[name], []

    def recalculated(book, application):      # verify's own, made for every book in one run
        asked.append((Path(book), application))
        return office.read_values(recalculated_by_libreoffice[name])
    monkeypatch.setattr(office, "recalculated_values", recalculated)
    report = verify(path, "libreoffice")
    assert asked == [(path, "libreoffice")]
    bad = [(c.name, m) for c in report.checks for m in c.mismatches[:2]]
    assert report.ok, bad[:5]
    assert report.cells == len(formula_cells(openpyxl.load_workbook(path)))


# ---------------------------------------------------------------- sliders' guides and blocks
def _drawn(path: Path) -> tuple[dict, dict]:
    """{drawn point name: (x, y)} as the book computes it, and the frame's grid square."""
    wb = openpyxl.load_workbook(path)
    values = engine.evaluate(wb)
    meta = read_meta(wb)
    pos, frame = meta["position"], meta["frames"]["frames"][0]
    points = {name: (values[("Mechanism", f"N{link['rows'][0] + k}")],
                     values[("Mechanism", f"O{link['rows'][0] + k}")])
              for link in pos["drawing"] for k, name in enumerate(link["joints"])}
    return points, values[(meta["frames"]["sheet"], frame["cells"]["square"])]


def test_a_slider_draws_its_guide_on_its_line_and_its_block_on_its_pin(bundled_books, capsys):
    """The slider-crank of Example 1 (offset a1 = 20 mm, published s14 = 273.9 at θ12 = 60°):
    the guide lies on the line y = 20 and spans the pin's travel; the block is 0.8 × 0.4 grid
    squares, centred on the pin B = (273.9, 20)."""
    path = bundled_books["slider-crank"]
    points, square = _drawn(path)
    (x1, y1), (x2, y2) = points["B guide 1"], points["B guide 2"]
    assert y1 == pytest.approx(20.0, abs=1e-9) and y2 == pytest.approx(20.0, abs=1e-9)
    assert x1 < 273.9 < x2            # the pin's least and greatest x over the sweep
    corners = np.array([points[f"B block {k}"] for k in range(1, 5)])
    assert corners.mean(axis=0) == pytest.approx([273.9, 20.0], abs=0.05)
    assert np.ptp(corners[:, 0]) == pytest.approx(0.8 * square)
    assert np.ptp(corners[:, 1]) == pytest.approx(0.4 * square)
    code, out, _ = _verify(path, capsys=capsys)
    assert code == 0, out


def test_the_guide_and_block_follow_an_edited_offset(bundled_books, tmp_path, capsys):
    """The slider line's offset a1 typed in as a user would: the guide moves onto y = 35 and
    the block with the pin; verify still agrees."""
    path = Path(shutil.copy(bundled_books["slider-crank"], tmp_path / "sc.xlsx"))
    wb = openpyxl.load_workbook(path)
    wb["Mechanism"]["C7"] = 35.0          # a1, the first input
    wb.save(path)
    points, _ = _drawn(path)
    assert points["B guide 1"][1] == pytest.approx(35.0) == points["B guide 2"][1]
    corners = np.array([points[f"B block {k}"] for k in range(1, 5)])
    assert corners.mean(axis=0) == pytest.approx(points["B"])
    code, out, _ = _verify(path, capsys=capsys)
    assert code == 0, out


def test_a_slide_draws_its_guide_through_the_block_on_the_moving_link(bundled_books, tmp_path,
                                                                        capsys):
    """The inverted slider-crank: the block at A slides on a line through B carried by link 4;
    the guide's ends, B and A lie on one line, at every input the book is set to."""
    path = Path(shutil.copy(bundled_books["inverted-slider-crank"], tmp_path / "isc.xlsx"))
    for angle in (30.0, 200.0):
        wb = openpyxl.load_workbook(path)
        wb["Mechanism"]["I7"] = angle
        wb.save(path)
        points, _ = _drawn(path)
        (ax, ay), (bx, by) = points["A"], points["B"]
        for end in ("B guide 1", "B guide 2"):
            gx, gy = points[end]
            cross = (gx - bx) * (ay - by) - (gy - by) * (ax - bx)
            assert abs(cross) < 1e-9 * 100 ** 2, (angle, end)
        code, out, _ = _verify(path, capsys=capsys)
        assert code == 0, out


@pytest.mark.parametrize("name, point, column, old, new", [
    ("toggle-press", "C block 2", "O", "+0.4*", "-0.4*"),      # a sign in the block's formula
    ("slider-crank", "B guide 1", "N", "MIN(", "MAX("),   # the guide's reach
    ("inverted-slider-crank", "A block 3", "N", "-0.2*", "+0.2*")])
def test_verify_finds_a_broken_guide_or_block_formula(name, point, column, old, new,
                                                      bundled_books, tmp_path, capsys):
    path = tmp_path / f"{name}.xlsx"
    wb = openpyxl.load_workbook(bundled_books[name])
    ws = wb["Mechanism"]
    row = next(r for r in range(1, ws.max_row + 1) if ws[f"M{r}"].value == point)
    cell = ws[f"{column}{row}"]
    assert old in cell.value, f"{point}: no {old!r} in {cell.value}"
    cell.value = cell.value.replace(old, new, 1)
    wb.save(path)
    code, out, _ = _verify(path, capsys=capsys)
    assert code == 1, out
    assert f"Mechanism!{column}{row}" in out and "likely cause" in out


def _dead_cells(report: dict) -> dict:
    return {(c["block"], c["column"]): c["dead_centre"] for c in report["checks"]
            if c["dead_centre"]}


def test_a_ram_pin_at_infinity_leaves_only_what_it_reaches_undetermined(tmp_path, capsys):
    """The shaper with |O1O2| = 20 mm and its 40 mm crank: at θ2 = 210° and 330°, both on the
    sweep, the lever lies parallel to the ram line, and the ram pin B is where a round-off
    determinant puts it (some 1e17 mm, either sign: the book and the reference differ). The
    ram line and the slot B slides on run over its least to its greatest travel, and the
    drawing's x extent takes it in: those are not determined (#N/A or any number, as a rate at
    a dead centre). The ram's own cells on those two rows, and its least and greatest travel
    in the summary, are named as not judged (their rounding bound is beyond their value:
    exit 2), and every other cell is judged and agrees; every force on those rows is not
    determined either (the shaper has masses and a cutting force). The bundled shaper
    (|O1O2| = 60 mm) never gets there: nothing left undetermined."""
    source = next(p for p in templates.bundled() if p.stem == "shaper")
    text = source.read_text(encoding="utf-8")
    near = text.replace('between the pivots", unit = "mm", value = 60.0',
                        'between the pivots", unit = "mm", value = 20.0')
    assert near != text
    reports = {}
    for name, body in (("bundled", text), ("near", near)):
        toml, path = tmp_path / f"{name}.toml", tmp_path / f"{name}.xlsx"
        toml.write_text(body, encoding="utf-8")
        assert main(["build", str(toml), "-o", str(path)]) == 0
        capsys.readouterr()
        code, out, _ = _verify(path, "--json", capsys=capsys)
        reports[name] = json.loads(out)[0]
        assert code == {"bundled": 0, "near": 2}[name], out
    assert _dead_cells(reports["bundled"]) == {} and reports["bundled"]["not_judged"] == []
    guide_ends = 4 * 2        # B guide 1, 2 and B slot 1, 2, x and y each
    # every force on those two rows (the effort, the pins, the guides, the shaking force): what
    # the slot's push on the ram pin reaches, its determinant zero there; not the centres'
    # places and accelerations
    forces = {c["column"] for c in reports["near"]["checks"] if c["block"] == "Forces"
              and c["column"][0] in "FNTs"}
    assert _dead_cells(reports["near"]) == {
        ("joints", "drawing rows"): guide_ends, ("frame", "drawing: extents"): 2,
        ("frame", "drawing: links x"): guide_ends // 2,
        ("frame", "drawing: links y"): guide_ends // 2,
        **{("Forces", column): 2 for column in forces}}
    assert {"T12", "F35", "N35", "shaking_moment"} <= forces
    assert reports["near"]["mismatches"] == 0 and not reports["near"]["unjudged"]
    assert reports["near"]["not_judged"]
    wb = openpyxl.load_workbook(tmp_path / "near.xlsx")
    parallel = {"Sweep": {r for r in range(5, wb["Sweep"].max_row + 1)
                          if wb["Sweep"][f"A{r}"].value in (210, 330)}}
    parallel["Motion"] = {r for r in range(7, wb["Motion"].max_row + 1)
                          if wb["Motion"][f"A{r}"].value in
                          {f"='Sweep'!A{s}" for s in parallel["Sweep"]}}
    assert all(len(rows) == 2 for rows in parallel.values())
    for where in reports["near"]["not_judged"]:
        sheet, cells = where.split("!")
        for cell in cells.split(":"):
            row = openpyxl.utils.cell.coordinate_from_string(cell)[1]
            if sheet == "Mechanism":       # the summary: the ram's least and greatest travel
                assert "r5 (ram position" in wb[sheet][f"A{row}"].value, where
            else:
                assert row in parallel[sheet], where
