"""Form controls in the file (the textbook's spin button), and packages Excel's validator accepts.

- LibreOffice, through its own API (UNO, tests/uno_probe.py run by the Python that has Debian's
  python3-uno), loads a built book, finds the controls, reads their type, range and linked cell,
  moves them, and the input cell and the drawing's joint coordinates follow: checked against the
  independent reference at the new input.
- `openxml-audit` (a port of the Open XML SDK validator) finds no error and no warning in any
  bundled book, plain or with cached values.
"""
from __future__ import annotations

import json
import re
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import openpyxl
import pytest
from conftest import HANG_GUARD_S, UNO_PYTHON, template

from linkbook.book import builder
from linkbook.book import package
from linkbook.check import verifier
from linkbook.book.controls import Control

PROBE = Path(__file__).with_name("uno_probe.py")
BUNDLED = sorted(p.stem for p in Path(__file__).resolve().parents[1].glob("templates/*.toml"))


def _build(tmp_path: Path, name: str, sets=(), values=False) -> tuple[Path, object]:
    path = tmp_path / f"{name}{'-values' if values else ''}.xlsx"
    built = builder.build_file(template(name, sets), path, with_values=values)
    return path, built


# ---------------------------------------------------------------- Open XML validity
@pytest.mark.slow        # the Open XML validator on every book
@pytest.mark.parametrize("values", [False, True], ids=["plain", "values"])
@pytest.mark.parametrize("name", BUNDLED)
def test_openxml_audit_finds_nothing(tmp_path, name, values):
    from openxml_audit import OpenXmlValidator
    path, _ = _build(tmp_path, name, values=values)
    result = OpenXmlValidator().validate(path)
    found = [f"{e.severity.value}: {e.description} ({e.part_uri} {e.path})" for e in result.errors]
    assert result.is_valid and not found, "\n".join(found[:10])


def test_the_validator_sees_the_controls(tmp_path):
    """The check above is only worth something if the validator reads the parts we add."""
    from openxml_audit import OpenXmlValidator
    path, _ = _build(tmp_path, "fourbar")
    bad = tmp_path / "bad.xlsx"
    with zipfile.ZipFile(path) as zin, zipfile.ZipFile(bad, "w") as zout:
        for info in zin.infolist():
            data = zin.read(info)
            if info.filename.startswith("xl/ctrlProps/"):
                data = data.replace(b'objectType="', b'objectType="X')
            zout.writestr(info, data)
    assert not OpenXmlValidator().validate(bad).is_valid


# ---------------------------------------------------------------- the package pass
def test_text_cells_become_shared_strings(tmp_path):
    wb = openpyxl.Workbook()
    ws = wb.active
    texts = ["plain", "  leading and trailing  ", "a & b < c", "θ13 [deg]", "plain", "x\ny"]
    for i, text in enumerate(texts, start=1):
        ws[f"A{i}"] = text
    ws["B1"] = "=A1"
    src = tmp_path / "in.xlsx"
    wb.save(src)
    out = tmp_path / "out.xlsx"
    package.finish(src, out)
    with zipfile.ZipFile(out) as z:
        sheet = z.read("xl/worksheets/sheet1.xml")
        sst = z.read("xl/sharedStrings.xml")
        assert b"inlineStr" not in sheet and b'<f>A1</f>' in sheet
        assert b'count="6" uniqueCount="5"' in sst
        assert b"sharedStrings" in z.read("[Content_Types].xml")
        assert b"sharedStrings" in z.read("xl/_rels/workbook.xml.rels")
    again = openpyxl.load_workbook(out).active
    assert [again[f"A{i}"].value for i in range(1, len(texts) + 1)] == texts


def test_font_children_in_schema_order():
    styles = (b'<styleSheet><fonts count="2"><font><name val="Calibri"/><family val="2"/>'
              b'<color theme="1"/><sz val="11"/><scheme val="minor"/></font>'
              b'<font><b val="1"/><sz val="14"/></font></fonts></styleSheet>')
    assert package.fonts_in_order(styles) == (
        b'<styleSheet><fonts count="2"><font><sz val="11"/><color theme="1"/><name val="Calibri"/>'
        b'<family val="2"/><scheme val="minor"/></font>'
        b'<font><b val="1"/><sz val="14"/></font></fonts></styleSheet>')


def test_controls_in_the_package(tmp_path):
    """The pump: a scroll bar and a spin button on the input angle, a spin button on s1; each
    part where Excel expects it, numbered after what the package already has."""
    path, built = _build(tmp_path, "pump")
    records = built.meta["controls"]["Mechanism"]
    assert [(c["kind"], c["cell"], c["min"], c["max"], c["page"]) for c in records] == [
        ("Scroll", "I7", 0, 360, 20), ("Spin", "I7", 0, 360, 20),
        ("Spin", built.meta["inputs"]["s1"]["cell"], 20, 250, 1)]
    with zipfile.ZipFile(path) as z:
        sheet = z.read("xl/worksheets/sheet1.xml").decode()
        rels = z.read("xl/worksheets/_rels/sheet1.xml.rels").decode()
        vml = z.read("xl/drawings/vmlDrawing1.vml").decode()
        props = [z.read(f"xl/ctrlProps/ctrlProp{i}.xml").decode() for i in (1, 2, 3)]
    assert sheet.index("<drawing ") < sheet.index("<legacyDrawing ") < sheet.index("<controls>")
    assert sheet.endswith("</worksheet>")
    assert len(re.findall(r"<control shapeId=", sheet)) == 3
    assert rels.count("relationships/ctrlProp") == 3 and "vmlDrawing1.vml" in rels
    assert vml.count("<x:FmlaLink>$I$7</x:FmlaLink>") == 2 and vml.count("<x:Horiz/>") == 1
    assert 'objectType="Spin"' in props[2] and 'fmlaLink="$C$12"' in props[2]


def test_controls_added_to_a_sheet_without_relationships(tmp_path):
    wb = openpyxl.Workbook()
    wb.active["A1"] = 5
    src, out = tmp_path / "in.xlsx", tmp_path / "out.xlsx"
    wb.save(src)
    spin = Control("Spin", "A1", 0, 10, 1, 2, 5, (1, 0, 0, 0, 1, 20, 2, 0))
    package.finish(src, out, controls={"Sheet": [spin]})
    with zipfile.ZipFile(out) as z:
        rels = z.read("xl/worksheets/_rels/sheet1.xml.rels").decode()
        assert 'Id="rId1"' in rels and 'Id="rId2"' in rels
        assert 'r:id="rId1"/>' in z.read("xl/worksheets/sheet1.xml").decode()
        assert "xl/drawings/vmlDrawing1.vml" in z.namelist()


# ---------------------------------------------------------------- LibreOffice's own view
def _probe(path: Path, moves, cells) -> dict:
    run = subprocess.run([UNO_PYTHON, str(PROBE), str(path), "Mechanism", json.dumps(moves),
                          json.dumps(cells)], capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert run.returncode == 0, run.stderr[-2000:]
    return json.loads(run.stdout.strip().splitlines()[-1])


def _cell_index(cell: str) -> list[int]:
    col, row = openpyxl.utils.cell.coordinate_from_string(cell)
    return [0, openpyxl.utils.column_index_from_string(col) - 1, row - 1]


def _expected_joints(built, inputs: dict, angle: float) -> dict[str, tuple[float, float]]:
    ref = verifier.Reference(built.record).solve(inputs, np.array([angle]))
    return {name: (float(x[0]), float(y[0])) for name, (x, y) in ref["points"].items()}


@pytest.mark.libreoffice
@pytest.mark.parametrize("name, values", [("fourbar", False), ("pump", False), ("fourbar", True)],
                         ids=["fourbar", "pump", "fourbar-values"])
def test_libreoffice_moves_the_drawing_with_the_controls(needs, tmp_path, name, values):
    needs("libreoffice", "uno")
    path, built = _build(tmp_path, name, values=values)
    records = built.meta["controls"]["Mechanism"]
    joints = built.meta["position"]["joints"]
    cells = ["I7"] + [c for xy in joints.values() for c in xy]
    grid_cell = built.meta["inputs"]["s1"]["cell"] if name == "pump" else None
    # scroll bar to 200°, then the spin button to 95°, then (pump) the s1 spin button to 100.
    moves = [[0, 200], [1, 95]] + ([[2, 100]] if grid_cell else [])
    report = _probe(path, moves, cells + ([grid_cell] if grid_cell else []))

    found = report["controls"]
    assert [c["kind"] for c in found] == [r["kind"] for r in records]
    for got, want in zip(found, records):
        assert got["cell"] == _cell_index(want["cell"])
        assert (got["min"], got["max"], got["inc"], got["value"]) == (
            want["min"], want["max"], want["inc"], want["value"])
        assert got["printable"]
        if got["kind"] == "Scroll":
            assert got["page"] == want["page"] and got["horizontal"]

    inputs = verifier.inputs_of(built.workbook, built.record)
    for move, after in zip(moves, report["after"]):
        angle = move[1] if move[0] < 2 else 95
        if move[0] == 2:
            inputs = {**inputs, "s1": 100.0}
            assert after[grid_cell] == 100
        assert after["I7"] == angle
        expected = _expected_joints(built, inputs, angle)
        for joint, (cx, cy) in joints.items():
            ex, ey = expected[joint]
            assert after[cx] == pytest.approx(ex, abs=1e-9 * 300)
            assert after[cy] == pytest.approx(ey, abs=1e-9 * 300)
    moved = [j for j, (cx, _) in joints.items()
             if report["before"][cx] != report["after"][0][cx]]
    assert len(moved) >= 2, "the drawing did not move"
