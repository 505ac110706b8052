"""Damaged and edited workbooks, and damaged templates: every one gets a clear answer.

`linkbook verify` of a mutated bundled book ends with exit 0, 1 or 2 and one clear last line,
never a traceback, within 20 s; `linkbook build` of a mutated template ends with 0 or 2. The
mutations are drawn by hypothesis (derandomized, so CI sees the same ones): workbook edits as
people make them (a defined name deleted, formulas replaced by any formula of Excel's functions,
input cells made huge, negative, text or formulas, sheets renamed or deleted, the build record
cut) and package damage (parts dropped, cut short or scrambled; a sheet renamed in the XML;
content types, relationships, styles, charts and shared strings broken). Parametrized cases
add what the spreadsheet application reads otherwise than Python would: a sheet-scoped
namesake of an input, a name defined twice (case too), an input stored as another text, a
DTD anywhere in a part.
"""
from __future__ import annotations

import io
import json
import math
import re
import time
import tomllib
import zipfile
from pathlib import Path

import openpyxl
import pytest
from conftest import examples, template
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linkbook.book import builder
from linkbook.apps import cli
from linkbook.base import sheets as layout
from linkbook.base.sheets import write_meta_json

# hundreds of damaged books and templates: the full suite (CI) runs it, the fast tier leaves it out
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
SECONDS = 20        # of CPU time (this process's): the machine's load does not count
# Example counts: examples(n), sized by the hypothesis profile (tests/conftest.py).
FUNCTIONS = """ABS ACOS ACOSH AND ASIN ATAN ATAN2 AVERAGE CEILING CHOOSE COLUMN CONCATENATE COS
COUNT COUNTA COUNTIF DEGREES EXP FACT FILTER FIND FLOOR IF IFERROR IFNA INDEX INDIRECT INT
ISERROR ISNA LEFT LEN LET LN LOG LOG10 LOOKUP MATCH MAX MAXIFS MEDIAN MID MIN MINIFS MOD NA
NOT NOW OFFSET OR PI POWER PRODUCT RADIANS RAND RANDBETWEEN ROUND ROW SEQUENCE SIGN SIN SQRT
STDEV SUM SUMPRODUCT TAN TEXT TODAY TRANSPOSE VALUE VLOOKUP XLOOKUP""".split()
ARGUMENTS = ["A1", "Sweep!B5", "Sweep!B5:B9", "a_2", "no_such_name", "1e308", "-1", "0",
             '"x"', "TRUE", "#N/A", "A:A", "1:1", "Nowhere!A1", "'Sweep'!$C$5", "Mechanism!I7"]


class Raw(bytes):
    def __repr__(self) -> str:          # hypothesis prints the arguments of a failing example
        return f"<{len(self)} bytes>"


@pytest.fixture(scope="module")
def books(tmp_path_factory) -> dict[str, bytes]:
    """Small bundled books (coarse steps: many mutations in little time), as file bytes."""
    folder = tmp_path_factory.mktemp("fuzz")
    out = {}
    for name, sets, step in (("fourbar", (), 30.0), ("pump", ("s1=20,100",), 60.0),
                             ("boom-cylinder", (), 100.0)):
        path = folder / f"{name}.xlsx"
        builder.build_file(template(name, sets, step), path)
        out[name] = Raw(path.read_bytes())
    return out


def _run(argv: list[str], capsys) -> tuple[int, str]:
    start = time.process_time()
    code = cli.main(argv)
    took = time.process_time() - start
    captured = capsys.readouterr()
    text = captured.out + captured.err
    assert took < SECONDS, f"took {took:.1f} s of CPU"
    return code, text


def _clear_answer(code: int, text: str, allowed=(0, 1, 2)) -> None:
    assert code in allowed, (code, text[-500:])
    assert "Traceback" not in text and "internal error" not in text, text[-2000:]
    lines = [line for line in text.strip().splitlines() if line.strip()]
    assert lines, "no answer printed"
    last = lines[-1]
    if code == 0:
        assert last.startswith("all agree:"), last
    elif code == 1:
        assert last.startswith("DISAGREES:"), last
    else:
        assert last.startswith(("linkbook: error:", "CANNOT JUDGE")), last
    assert len(last) < 2000


# ---------------------------------------------------------------- workbook edits
FORMULA = st.builds(lambda f, args: f"={f}({','.join(args)})", st.sampled_from(FUNCTIONS),
                    st.lists(st.sampled_from(ARGUMENTS), max_size=3))
ODD_FORMULA = st.sampled_from(['=INDIRECT("A1")', "=SUM(A:A)", "=no_such_name+1", "=1/0",
                               '="text"', "=SQRT(-1)", "=I7", "=Sweep!B5", "=#REF!",
                               "=1E+308*10", "=A1:B2", "=", "=((", '=CHAR(0)'])
ODD_VALUE = st.sampled_from([1e308, -1e308, 1e-308, -5.0, 0.0, 1e30, 1e155, "abc", "", True,
                             None, "=1+1", "=C7", "  12  ", "1e3", 10 ** 30])


def _formula_cells(wb) -> list[tuple[str, str]]:
    return sorted((ws.title, c.coordinate) for ws in wb.worksheets
                  for c in ws._cells.values() if c.data_type == "f")


def _edit_book(wb, data) -> str:
    kind = data.draw(st.sampled_from(["name", "formula", "odd formula", "input", "sheet title",
                                      "drop sheet", "record", "record json", "position"]))
    cells = _formula_cells(wb)
    if kind == "name":
        names = sorted(wb.defined_names)
        if names:
            del wb.defined_names[data.draw(st.sampled_from(names))]
    elif kind in ("formula", "odd formula"):
        if not cells:
            return kind
        sheet, cell = data.draw(st.sampled_from(cells))
        wb[sheet][cell] = data.draw(FORMULA if kind == "formula" else ODD_FORMULA)
    elif kind == "input" and layout.MECH in wb.sheetnames:
        meta = layout.read_meta(wb)
        try:
            inputs = sorted(info["cell"] for info in meta["inputs"].values())
        except (TypeError, KeyError, AttributeError):     # a record damaged by an earlier edit
            inputs = ["C7"]
        wb[layout.MECH][data.draw(st.sampled_from(inputs))] = data.draw(ODD_VALUE)
    elif kind == "position" and layout.MECH in wb.sheetnames:
        wb[layout.MECH]["I7"] = data.draw(ODD_VALUE)
    elif kind == "sheet title":
        ws = wb[data.draw(st.sampled_from(wb.sheetnames))]
        ws.title = data.draw(st.sampled_from(["Renamed", "Sweep 2", "Ünïcode", "x"]))
    elif kind == "drop sheet" and len(wb.sheetnames) > 1:
        del wb[data.draw(st.sampled_from(wb.sheetnames))]
    elif kind == "record" and layout.META in wb.sheetnames and layout.read_meta(wb):
        meta = layout.read_meta(wb)
        path = data.draw(st.sampled_from(["sweep", "position", "inputs", "motion", "summary",
                                          "mechanism", "controls", "constants"]))
        meta[path] = data.draw(st.sampled_from([None, {}, [], 7, "x", {"rows": [5, 10 ** 9]}]))
        del wb[layout.META]
        write_meta_json(wb.create_sheet(layout.META), meta)
    elif kind == "record json" and layout.META in wb.sheetnames:
        ws = wb[layout.META]
        ws["A2"] = str(ws["A2"].value)[:data.draw(st.integers(0, 200))]
    return kind


@settings(max_examples=examples(200), derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_verify_of_an_edited_book_answers_clearly(books, tmp_path, capsys, data):
    name = data.draw(st.sampled_from(sorted(books)))
    wb = openpyxl.load_workbook(io.BytesIO(books[name]))
    for _ in range(data.draw(st.integers(1, 2))):
        _edit_book(wb, data)
    path = tmp_path / "edited.xlsx"
    wb.save(path)
    _clear_answer(*_run(["verify", str(path)], capsys))


# ---------------------------------------------------------------- package damage
def _damage_package(raw: bytes, data) -> bytes:
    src = zipfile.ZipFile(io.BytesIO(raw))
    names = src.namelist()
    kind = data.draw(st.sampled_from(["drop", "cut part", "scramble", "sheet name", "types",
                                      "rels", "styles", "chart", "strings", "cut file",
                                      "empty part"]))
    if kind == "cut file":
        return raw[:data.draw(st.integers(0, len(raw) - 1))]
    target = {"types": "[Content_Types].xml", "rels": "xl/_rels/workbook.xml.rels",
              "styles": "xl/styles.xml", "strings": "xl/sharedStrings.xml",
              "sheet name": "xl/workbook.xml",
              "chart": "xl/charts/chart1.xml"}.get(kind) or data.draw(st.sampled_from(names))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            body = src.read(info)
            if info.filename == target:
                if kind == "drop":
                    continue
                body = _damage_part(kind, body, data)
            dst.writestr(info.filename, body)
    return out.getvalue()


def _damage_part(kind: str, body: bytes, data) -> bytes:
    if kind in ("cut part", "styles", "chart", "types", "rels"):
        return body[:data.draw(st.integers(0, max(0, len(body) - 1)))]
    if kind == "empty part":
        return b""
    if kind == "scramble":
        at = data.draw(st.integers(0, max(0, len(body) - 1)))
        return body[:at] + data.draw(st.binary(min_size=1, max_size=8)) + body[at + 1:]
    if kind == "sheet name":
        return re.sub(rb'name="Sweep"', b'name="Swept"', body, count=1)
    if kind == "strings":
        return re.sub(rb"<si>.*?</si>", b"<si><t>changed</t></si>", body, count=3)
    return body


@settings(max_examples=examples(100), derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_verify_of_a_damaged_package_answers_clearly(books, tmp_path, capsys, data):
    name = data.draw(st.sampled_from(sorted(books)))
    path = tmp_path / "damaged.xlsx"
    path.write_bytes(_damage_package(books[name], data))
    _clear_answer(*_run(["verify", str(path)], capsys))


def test_the_known_cases(books, tmp_path, capsys):
    """The issue's examples: an unknown name, INDIRECT, a whole column, a renamed sheet."""
    for formula, says in (("=a_2*2", "the name a_2 is not defined"),
                          ('=INDIRECT("A1")', "(INDIRECT, OFFSET) cannot be evaluated"),
                          ("=SUM(A:A)", "a whole row or column")):
        wb = openpyxl.load_workbook(io.BytesIO(books["fourbar"]))
        del wb.defined_names["a_2"]
        wb["Mechanism"]["I9"] = formula
        path = tmp_path / "case.xlsx"
        wb.save(path)
        code, text = _run(["verify", str(path)], capsys)
        assert code == 2 and "Mechanism!I" in text and says in text, text


# ------------------------------------------------- what the application reads otherwise
def _rewritten(raw: bytes, part: str, edit) -> bytes:
    """The book with `edit` (bytes -> bytes) applied to one part."""
    src = zipfile.ZipFile(io.BytesIO(raw))
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            body = src.read(info)
            dst.writestr(info.filename, edit(body) if info.filename == part else body)
    return out.getvalue()


def _first_name(body: bytes) -> re.Match:
    """The first workbook-scoped name of workbook.xml (an input of every bundled book)."""
    return re.search(rb'<definedName name="([^"]+)">([^<]+)</definedName>', body)


def _add_name(body: bytes, name: bytes, target: bytes, scope: bytes = b"",
              before: bool = False) -> bytes:
    m = _first_name(body)
    added = b'<definedName name="' + name + b'"' + scope + b">" + target + b"</definedName>"
    at = m.start() if before else m.end()
    return body[:at] + added + body[at:]


NAME_EDITS = {
    # a sheet-scoped namesake pointing elsewhere: that sheet's formulas would read it
    "scoped": lambda b: _add_name(b, _first_name(b)[1], b"'Mechanism'!$A$1",
                                  b' localSheetId="1"'),
    "scoped, other case": lambda b: _add_name(b, _first_name(b)[1].upper(), b"'Mechanism'!$A$1",
                                              b' localSheetId="2"'),
    # a second definition before the first: the application reads the first it meets
    "defined twice": lambda b: _add_name(b, _first_name(b)[1], b"'Mechanism'!$A$1", before=True),
    "twice, other case": lambda b: _add_name(b, _first_name(b)[1].upper(), b"'Mechanism'!$A$1",
                                             before=True),
}


@pytest.mark.parametrize("edit", sorted(NAME_EDITS))
@pytest.mark.parametrize("name", ["fourbar", "pump", "boom-cylinder"])
def test_an_ambiguous_name_is_refused(books, tmp_path, capsys, name, edit):
    path = tmp_path / "names.xlsx"
    path.write_bytes(_rewritten(books[name], "xl/workbook.xml", NAME_EDITS[edit]))
    code, text = _run(["verify", str(path)], capsys)
    _clear_answer(code, text)
    assert code == 2 and "xl/workbook.xml: the name" in text, text


_NUMBER_CELL = re.compile(rb'(<c r="C\d+"[^>]* t="n"><v>)([^<]+)(</v>)')
REFUSED_NUMBERS = ["3_5", "３５", "0x10", "35.0.0", "1e999", "-1e999", "INF", "NaN", "", "1 0",
                   "١٢", "1e", ".", "+", "--1", "0b1"]
SAME_NUMBER = [" {}", "{} ", "\t{}\n", "+{}", "{}.0", "{}e0", "0{}"]


@pytest.mark.parametrize("literal", REFUSED_NUMBERS + SAME_NUMBER)
@pytest.mark.parametrize("name", ["fourbar", "boom-cylinder"])
def test_an_input_number_is_read_as_the_application_reads_it(books, tmp_path, capsys, name,
                                                              literal):
    """The first input of the Mechanism sheet, stored as another text: one the application
    reads as the same number gives the clean book's answer, any other is refused."""
    raw = books[name]
    original = _NUMBER_CELL.search(zipfile.ZipFile(io.BytesIO(raw)).read(
        "xl/worksheets/sheet1.xml"))[2].decode()
    stored = literal.format(original)

    def edit(body: bytes) -> bytes:
        return _NUMBER_CELL.sub(lambda m: m[1] + stored.encode() + m[3], body, count=1)
    path = tmp_path / "number.xlsx"
    path.write_bytes(_rewritten(raw, "xl/worksheets/sheet1.xml", edit))
    code, text = _run(["verify", str(path)], capsys)
    _clear_answer(code, text)
    if literal in SAME_NUMBER:
        assert code == 0, text
    elif stored == "":
        assert code == 2, text           # an empty input cell: refused as no number
    else:
        assert code == 2 and f"holds {stored!r}" in text, text


LONG_COMMENT = b"<!-- " + b"-x" * 4000 + b" -->"


@pytest.mark.parametrize("where", ["after a long comment", "at the end", "utf-16"])
@pytest.mark.parametrize("part", ["xl/worksheets/sheet2.xml", "xl/styles.xml",
                                  "[Content_Types].xml", "xl/drawings/vmlDrawing1.vml"])
def test_a_dtd_is_refused_wherever_it_is(books, tmp_path, capsys, part, where):
    dtd = b'<!DOCTYPE x [<!ENTITY e "1">]>'

    def edit(body: bytes) -> bytes:
        if where == "at the end":
            return body + LONG_COMMENT + dtd
        at = re.search(rb"<[A-Za-z]", body).start()
        body = body[:at] + LONG_COMMENT + dtd + body[at:]
        return body.decode().encode("utf-16") if where == "utf-16" else body
    path = tmp_path / "dtd.xlsx"
    path.write_bytes(_rewritten(books["fourbar"], part, edit))
    code, text = _run(["verify", str(path)], capsys)
    _clear_answer(code, text)
    assert code == 2 and f"part {part} declares a DTD" in text, text


# ---------------------------------------------------------------- templates
def _mutate_toml(doc: dict, data) -> dict:
    kind = data.draw(st.sampled_from(["drop table", "drop key", "wrong type", "huge list",
                                      "unicode", "extreme", "empty"]))
    if kind == "empty" or not doc:
        return {}
    tables = [k for k, v in doc.items() if isinstance(v, dict)] or list(doc)
    table = data.draw(st.sampled_from(tables))
    if kind == "drop table":
        doc.pop(table, None)
        return doc
    body = doc.get(table)
    keys = sorted(body) if isinstance(body, dict) and body else None
    if kind == "drop key" and keys:
        body.pop(data.draw(st.sampled_from(keys)))
    elif kind == "wrong type":
        value = data.draw(st.sampled_from(["x", 1, 1.5, True, [], {}, [1, "a"], {"a": {}}]))
        if keys:
            body[data.draw(st.sampled_from(keys))] = value
        else:
            doc[table] = value
    elif kind == "huge list" and keys:
        body[data.draw(st.sampled_from(keys))] = list(range(data.draw(st.integers(0, 5000))))
    elif kind == "unicode" and keys:
        key = data.draw(st.sampled_from(keys))
        text = data.draw(st.text(min_size=0, max_size=40))
        if isinstance(body[key], dict) and "label" in body[key]:
            body[key]["label"] = text
        else:
            body[text or "\u00e9"] = body.pop(key)
    elif kind == "extreme" and keys:
        key = data.draw(st.sampled_from(keys))
        number = data.draw(st.sampled_from([1e308, -1e308, 5e-324, 0.0, -0.0, 1e155, 1e-12,
                                            10 ** 40, -1, 3.6e6]))
        if isinstance(body[key], dict) and "value" in body[key]:
            body[key]["value"] = number
        else:
            body[key] = number
    return doc


def _toml(value, key_path=()) -> str:
    """A small TOML writer for the mutated documents (tables of scalars, lists, inline tables)."""
    lines, tables = [], []
    for k, v in value.items():
        if isinstance(v, dict) and not key_path:
            tables.append((k, v))
        else:
            lines.append(f"{json.dumps(str(k))} = {_inline(v)}")
    for k, v in tables:
        lines.append(f"[{json.dumps(str(k))}]")
        lines.extend(f"{json.dumps(str(kk))} = {_inline(vv)}" for kk, vv in v.items())
    return "\n".join(lines) + "\n"


def _inline(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_inline(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(str(k))} = {_inline(x)}" for k, x in v.items()) + "}"
    return json.dumps(str(v))


@settings(max_examples=examples(80), derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(data=st.data())
def test_build_of_a_damaged_template_answers_clearly(tmp_path, capsys, data):
    name = data.draw(st.sampled_from(["fourbar", "pump", "slider-crank", "boom-cylinder"]))
    doc = tomllib.loads((ROOT / "templates" / f"{name}.toml").read_text(encoding="utf-8"))
    doc.setdefault("sweep", {})["step"] = 60        # small books: many examples in little time
    for _ in range(data.draw(st.integers(1, 2))):
        doc = _mutate_toml(doc, data)
    src = tmp_path / "mutant.toml"
    src.write_text(_toml(doc), encoding="utf-8")
    out = tmp_path / "mutant.xlsx"
    out.unlink(missing_ok=True)          # tmp_path is shared by the examples
    code, text = _run(["build", str(src), "-o", str(out)], capsys)
    assert code in (0, 2), text[-1000:]
    assert "Traceback" not in text and "internal error" not in text, text[-2000:]
    last = text.strip().splitlines()[-1] if text.strip() else ""
    if code == 2:
        assert last.startswith("linkbook: error:") and not out.exists(), last
    else:
        assert last.startswith("wrote") and zipfile.is_zipfile(out)
