"""Text from a template is always text: a title, a label, a symbol or a chart title that starts
with '=', '+', '-' or '@' is written as a string cell, never as a live formula (the writer makes
a formula only of what linkbook itself built as one: package.Formula)."""
from __future__ import annotations

import re
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import pytest

from conftest import ROOT
import linkbook
from linkbook.engine import office

MAIN = "{http://schemas.openxmlformats.org/spreadsheetml/2006/main}"
FOURBAR_TOML = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")
# what spreadsheet applications take for the start of a formula (CSV injection's payloads)
PAYLOADS = ['=HYPERLINK("http://example.com","click")', "+cmd|' /C calc'!A0", "-2+3",
            "@SUM(1)", "=1+1", "=WEBSERVICE(\"http://example.com\")"]
# every text field a template fills a cell from
TEXT_KEYS = ("title", "source", "description", "label", "symbol", "x_title", "y_title")


def injected(payload: str) -> str:
    """fourbar.toml with every text field replaced by `payload` and the field's name (and a
    description, which fourbar has none of)."""
    text = FOURBAR_TOML.replace('source = "', 'description = "d"\nsource = "', 1)
    quoted = payload.replace("\\", "\\\\").replace('"', '\\"')
    pattern = r'\b(' + "|".join(TEXT_KEYS) + r')(\s*=\s*)"[^"]*"'
    return re.sub(pattern, lambda m: f'{m[1]}{m[2]}"{quoted} {m[1]}"', text)


def cells_of(path: Path) -> dict[tuple[str, str], tuple[str, str, str | None]]:
    """(sheet, cell) -> (t attribute, text of a string cell or of a formula, 'f' if a formula),
    read from the file's XML."""
    with zipfile.ZipFile(path) as zf:
        sst = [("".join(si.itertext())) for si in
               ElementTree.fromstring(zf.read("xl/sharedStrings.xml")).iter(f"{MAIN}si")]
        book = ElementTree.fromstring(zf.read("xl/workbook.xml"))
        rels = ElementTree.fromstring(zf.read("xl/_rels/workbook.xml.rels"))
        target = {r.get("Id"): r.get("Target") for r in rels}
        out = {}
        for sheet in book.iter(f"{MAIN}sheet"):
            rid = sheet.get("{http://schemas.openxmlformats.org/officeDocument/2006/"
                            "relationships}id")
            part = ElementTree.fromstring(zf.read("xl/" + target[rid].lstrip("/").removeprefix(
                "xl/")))
            for c in part.iter(f"{MAIN}c"):
                f = c.find(f"{MAIN}f")
                t = c.get("t", "n")
                if f is not None:
                    out[sheet.get("name"), c.get("r")] = (t, f.text or "", "f")
                elif t == "s":
                    out[sheet.get("name"), c.get("r")] = (t, sst[int(c.findtext(f"{MAIN}v"))],
                                                          None)
        return out


def _build(tmp_path: Path, payload: str, values: bool = False) -> Path:
    toml = tmp_path / "mine.toml"
    toml.write_text(injected(payload), encoding="utf-8")
    return linkbook.build(toml, tmp_path / "mine.xlsx", values=values)


@pytest.mark.parametrize("payload", PAYLOADS)
def test_every_text_field_is_a_string_cell(tmp_path, payload):
    path = _build(tmp_path, payload, values=payload == PAYLOADS[0])
    cells = cells_of(path)
    formulas = {k: text for k, (_, text, f) in cells.items() if f}
    assert not [k for k, text in formulas.items()
                if any(f"{payload[1:]} {key}" in text for key in TEXT_KEYS)], \
        "a template's text became a formula"
    texts = {k: text for k, (t, text, f) in cells.items() if not f and payload in text}
    assert all(cells[k][0] == "s" for k in texts)
    shown = {(sheet, cell) for sheet, cell in texts if sheet != "linkbook"}
    # the title on each sheet, the description and the source, every parameter's label, the
    # input's symbol and every column's label and header
    for where in (("Mechanism", "A1"), ("Mechanism", "A2"), ("Sweep", "A1"), ("Motion", "A1"),
                  ("Charts", "A1"), ("Mechanism", "A7"), ("Mechanism", "H7"), ("Sweep", "C3"),
                  ("Sweep", "C4")):
        assert where in shown, where
    assert texts["Mechanism", "A1"] == f"{payload} title"
    assert len(shown) >= 60
    report = linkbook.verify(path)
    assert report.status == 0 and not report.unjudged


@pytest.mark.libreoffice
def test_libreoffice_shows_the_text(needs, tmp_path):
    needs("libreoffice")
    payload = PAYLOADS[0]
    path = _build(tmp_path, payload)
    values = office.recalculated_values(path)
    assert values["Mechanism", "A1"] == f"{payload} title"
    assert values["Charts", "A1"] == f"{payload} title: charts (data on sheet Sweep)"
    assert values["Sweep", "C4"] == f"{payload} symbol [mm]"
