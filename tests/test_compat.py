"""Workbooks that compute the same in every spreadsheet application (issues 16 and 28): every
function of every bundled book, and every function a template's expression may use, is one that
Excel 2010, LibreOffice, Gnumeric and Google Sheets all document, with no `_xlfn.` prefix (a
function newer than Excel 2007, such as AGGREGATE, shows #NAME? in Gnumeric and IronCalc); an
ACOS, ASIN or SQRT is called only inside a test of its argument's domain, never trusted to raise
an error (IronCalc's ACOS(2) is a NaN that IFERROR lets through); an ATAN2 angle's cut never
falls on a sample, where applications that round a sine differently would differ by a turn.
"""
from __future__ import annotations

import math
import re

import pytest
from conftest import HANG_GUARD_S, built, checks_of
from openpyxl.utils import get_column_letter
from openpyxl.utils.cell import column_index_from_string, coordinate_from_string

from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.engine import office
from linkbook.language import templates
from linkbook.language.expressions import FUNCTIONS as EXPRESSION_FUNCTIONS
from linkbook.language.expressions import expression

# Functions that a linkage workbook could reasonably use, each documented by all of: Microsoft's
# "Excel functions (alphabetical)" (as in Excel 2007/2010), LibreOffice Calc's "Functions by
# Category", Gnumeric's function reference, and Google Sheets' "function list". Not the whole
# catalogue: a function outside this list fails the test until someone checks it in all four.
EVERYWHERE = {
    "ABS", "ACOS", "AND", "ASIN", "ATAN", "ATAN2", "AVERAGE", "CHOOSE", "COS", "COUNT",
    "COUNTA", "COUNTIF", "DEGREES", "EXP", "FIXED", "IF", "IFERROR", "INDEX", "INT", "ISERROR",
    "ISNA", "ISNUMBER", "LARGE", "LN", "LOG", "LOG10", "MATCH", "MAX", "MIN", "MOD", "NA", "NOT",
    "OR", "PI", "POWER", "RADIANS", "ROUND", "ROWS", "SIGN", "SIN", "SMALL", "SQRT", "SUM",
    "SUMPRODUCT", "TAN",
}
BUNDLED = [p.stem for p in templates.bundled()]
NON_GRASHOF = ("a1=100", "a2=60", "a3=50", "a4=40")     # closes over part of the turn only

_CALL = re.compile(r"((?:_xlfn\.)?[A-Za-z][A-Za-z0-9.]*)\(")
_STRING = re.compile(r'"(?:[^"]|"")*"')


def functions_of(wb) -> set[str]:
    return {name for ws in wb.worksheets for row in ws.iter_rows() for c in row
            if c.data_type == "f" for name in _CALL.findall(_STRING.sub('""', c.value))}


def formulas_of(wb):
    return [(ws.title, c.coordinate, c.value) for ws in wb.worksheets for row in ws.iter_rows()
            for c in row if c.data_type == "f"]


@pytest.mark.parametrize("name", BUNDLED)
def test_every_function_of_a_bundled_book_is_in_every_application(name):
    b, _ = built(name)
    used = functions_of(b.workbook)
    assert used <= EVERYWHERE, used - EVERYWHERE    # _xlfn.AGGREGATE among them, if it came back


def test_the_summary_needs_no_function_newer_than_excel_2010():
    """MINIFS/MAXIFS (Excel 2019) were what the summary used: the four-bar's summary is where a
    newer function would show up first."""
    b, _ = built("fourbar")
    assert not {f for f in functions_of(b.workbook) if "IFS" in f.upper()}


def test_an_expression_may_only_use_functions_every_application_has():
    assert set(EXPRESSION_FUNCTIONS) <= EVERYWHERE


# ---------------------------------------------------------------- domains
def _calls(text: str, function: str) -> list[str]:
    """The argument text of every call of `function` in a formula."""
    out = []
    for m in re.finditer(rf"(?<![A-Za-z0-9_.]){function}\(", text):
        depth, start = 1, m.end()
        for i in range(start, len(text)):
            depth += {"(": 1, ")": -1}.get(text[i], 0)
            if depth == 0:
                out.append(text[start:i])
                break
    return out


def _sum_of_squares(arg: str) -> bool:
    """a^2+b^2 (each term squared at the top level): never negative."""
    terms, depth, last = [], 0, 0
    for i, ch in enumerate(arg):
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch in "+-" and depth == 0 and i > 0:
            if ch == "-":
                return False
            terms.append(arg[last:i])
            last = i + 1
    terms.append(arg[last:])
    return all(t.endswith("^2") for t in terms)


_COSINE_RULE = re.compile(r"\((.+)\^2\+(.+)\^2-(.+)\^2\)/\(2\*\1\*\2\)")


def _triangle_tested(arg: str, text: str) -> bool:
    """A cosine rule's argument (b²+c²-a²)/(2bc) whose call sits in a test that its sides
    make a triangle, ABS(x-MAX(y,z))>MIN(y,z) with {x, y, z} its three sides: the domain of
    the argument, |b - c| <= a <= b + c, with one side written once."""
    sides = _COSINE_RULE.fullmatch(arg)
    if not sides:
        return False
    for m in re.finditer(r"IF\(ABS\((.+?)-MAX\((.+?),(.+?)\)\)>MIN\(\2,\3\),NA\(\),ACOS\(", text):
        if sorted(m.groups()) == sorted(sides.groups()) and \
                text[m.end():].startswith(arg + ")"):
            return True
    return False


@pytest.mark.parametrize("name", BUNDLED)
def test_acos_asin_and_sqrt_are_called_only_inside_a_test_of_their_domain(name):
    b, _ = built(name)
    unguarded = []
    for sheet, cell, text in formulas_of(b.workbook):
        for function, test in (("ACOS", "IF(ABS({0})>1,"), ("ASIN", "IF(ABS({0})>1,"),
                               ("SQRT", "IF({0}<0,")):
            for arg in _calls(text, function):
                if not (test.format(arg) in text or function == "SQRT" and _sum_of_squares(arg)
                        or function == "ACOS" and _triangle_tested(arg, text)):
                    unguarded.append(f"{sheet}!{cell}: {function}({arg})")
    assert not unguarded, unguarded[:5]


def test_an_expression_tests_the_domain_of_acos_asin_and_sqrt():
    symbols = {"a", "b"}
    assert expression("f", "ACOS(a/b)", symbols).text == \
        "IF(ABS({a}/{b})>1,NA(),ACOS({a}/{b}))"
    assert expression("f", "2*ASIN(a-b)", symbols).text == \
        "2*IF(ABS({a}-{b})>1,NA(),ASIN({a}-{b}))"
    assert expression("f", "SQRT(a-b)", symbols).text == "IF({a}-{b}<0,NA(),SQRT({a}-{b}))"


# ---------------------------------------------------------------- the cut of an ATAN2 angle
_WINDOW = re.compile(r"=MOD\(ATAN2\(.*\)(?:([+-])RADIANS\(([0-9.]+)\))?,2\*PI\(\)\)")


def _cut(formula: str) -> float | None:
    """Where an ATAN2 angle's formula puts its jump of a turn (radians), or None if it is not
    an ATAN2 angle."""
    if re.fullmatch(r"=ATAN2\(.*\)", formula):
        return math.pi
    m = _WINDOW.match(formula)
    if not m:
        return None
    shift = float(m[2] or 0.0) * (1 if m[1] == "+" else -1)
    return math.radians(-shift)


@pytest.mark.parametrize("name", BUNDLED)
def test_no_atan2_angle_of_the_sweep_sits_on_its_cut(name):
    """Every sample at least 1e-6 rad from the cut: an application whose sine of 180° rounds
    to the other sign (Gnumeric's SIN(PI()) < 0, Excel's > 0) still lands on the same side."""
    b, values = built(name)
    sweep = b.meta["sweep"]
    ws = b.workbook[sweep["sheet"]]
    r0, r1 = sweep["rows"]
    near = []
    for key, letter in sweep["columns"].items():
        cut = _cut(str(ws[f"{letter}{r0}"].value))
        if cut is None:
            continue
        for r in range(r0, r1 + 1):
            v = values[(sweep["sheet"], f"{letter}{r}")]
            if isinstance(v, float) and abs(math.remainder(v - cut, 2 * math.pi)) < 1e-6:
                near.append((key, r, v))
    assert not near, near[:5]


# ---------------------------------------------------------------- extents without AGGREGATE
def test_verify_judges_every_numbers_only_copy_and_names_a_wrong_one():
    """The copies MIN and MAX read (a number, or a dash where the column has #N/A) are
    formula cells like any other: verify judges each against the reference, so a copy that
    drops a number or keeps one the loop cannot have is named."""
    b, values = built("fourbar", NON_GRASHOF, 10)
    copies = b.meta["numbers_only"]
    assert {c["sheet"] for c in copies} == {"Sweep", "Drawing data"}
    cells = [(c["sheet"], f"{c['column']}{r}") for c in copies
             for r in range(c["rows"][0], c["rows"][1] + 1)]
    dashes = [k for k in cells if values[k] == "—"]
    numbers = [k for k in cells if isinstance(values[k], float)]
    assert dashes and numbers and len(dashes) + len(numbers) == len(cells)
    assert not [m for c in checks_of(b, values) for m in c.mismatches]
    tampered = dict(values)
    tampered[dashes[0]], tampered[numbers[0]] = 0.0, "—"
    named = {(m.sheet, m.cell) for c in checks_of(b, tampered) for m in c.mismatches}
    assert {dashes[0], numbers[0]} <= named


def test_a_sweep_where_no_loop_closes_reads_a_dash_and_a_frame_round_the_pivots():
    """MIN of ranges with no number is 0 in every application; the summary says so with a
    dash, and the drawing's frame still holds what is there (the fixed pivots and the crank)."""
    b, values = built("fourbar", ("a1=100", "a2=10", "a3=10", "a4=10"), 30)
    summary = b.meta["summary"]
    assert values[("Mechanism", summary["mu_min"]["cell"])] == "—"
    assert values[("Mechanism", summary["mu_max"]["cell"])] == "—"
    frame = b.meta["frames"]["frames"][0]["cells"]
    got = [values[("Drawing data", frame[k])] for k in ("xmin", "xmax", "ymin", "ymax")]
    assert got == [-10.0, 100.0, -10.0, 10.0]       # A0, B0 and the crank pin's circle
    assert not [m for c in checks_of(b, values) for m in c.mismatches]


# ---------------------------------------------------------------- IronCalc, a smoke test
# IronCalc's defects the bundled books meet, each with its upstream issue: what a cell that
# starts a chain of differing cells must show in the formula IronCalc reads back.
IRONCALC_DEFECTS = {
    # "-(A1^1.22) is parsed as (-A1)^1.22": it stores -((D5^2)*X) as -D5^2*X, which Excel's
    # precedence reads as (-D5)^2*X (ironcalc/IronCalc#483)
    483: re.compile(r"(?<![A-Za-z0-9_.)\]])-[A-Za-z$][A-Za-z0-9_$!.']*\^"),
}
ERROR_CODES = {"#N/A", "#NAME?", "#VALUE!", "#DIV/0!", "#NUM!", "#REF!", "#NULL!", "#ERROR!"}


def _code(value) -> str | None:
    return engine.error_code(value) or office.error_code(value)


def _same(a, b) -> bool:
    if _code(a) or _code(b):
        return _code(a) == _code(b)
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-9)
    return a == b


def _ironcalc_values(ironcalc, path) -> tuple[dict, dict]:
    """Every cell's value after IronCalc's own evaluation, and the formula it read."""
    model = ironcalc.load_from_xlsx(str(path), "en", "UTC")
    model.evaluate()
    names = [p["name"] for p in model.get_worksheets_properties()]
    values, formulas = {}, {}
    for sheet, row, col in model.get_all_cells():
        key = (names[sheet], f"{get_column_letter(col)}{row}")
        v = model.get_cell_value(sheet, row, col)
        if isinstance(v, str) and v in ERROR_CODES:
            v = office.CellError(v)
        elif isinstance(v, int) and not isinstance(v, bool):
            v = float(v)
        values[key], formulas[key] = v, model.get_cell_content(sheet, row, col)
    return values, formulas


def _reads(rect, key) -> bool:
    """Whether a rectangle (sheet, top, left, bottom, right) that a formula reads holds key."""
    letters, row = coordinate_from_string(key[1])
    sheet, top, left, bottom, right = rect
    return sheet == key[0] and top <= row <= bottom and \
        left <= column_index_from_string(letters) <= right


@pytest.mark.slow        # IronCalc on every book
@pytest.mark.parametrize("name", BUNDLED)
def test_ironcalc_computes_every_bundled_book_as_linkbook_does(needs, bundled_books, name):
    """A fourth application as a smoke test: no #NAME?, and every chain of cells where
    IronCalc differs from linkbook starts at a formula that shows one of IronCalc's own
    defects as IronCalc reads it back (the cells downstream differ because they read it)."""
    needs("ironcalc")
    import ironcalc
    b, ours = built(name)
    theirs, read_back = _ironcalc_values(ironcalc, bundled_books[name])
    assert not [k for k, v in theirs.items() if _code(v) == "#NAME?"]
    differ = {k for k in ours if not _same(ours[k], theirs.get(k))}
    reads = engine.cells_read(b.workbook, differ)
    starts = [k for k in sorted(differ) if not any(
        _reads(rect, other) for rect in reads.get(k, []) for other in differ - {k})]
    unexplained = [(k, read_back.get(k)) for k in starts
                   if not any(p.search(str(read_back.get(k))) for p in IRONCALC_DEFECTS.values())]
    assert not unexplained, unexplained[:3]


# ---------------------------------------------------------------- charts in Gnumeric
def test_every_drawing_and_chart_part_declares_its_prefixes_on_its_root(tmp_path):
    """Gnumeric's reader knows only the namespace prefixes a part declares on its root element;
    openpyxl declares a:, c: and r: where it first uses them, and Gnumeric dropped every chart."""
    import zipfile
    path = tmp_path / "fourbar.xlsx"
    builder.build_file(templates.load("fourbar"), path)
    with zipfile.ZipFile(path) as z:
        parts = [n for n in z.namelist() if re.fullmatch(r"xl/(drawings|charts)/[^/]+\.xml", n)]
        assert len(parts) > 2
        for name in parts:
            xml = z.read(name).decode()
            root_end = xml.index(">", xml.index("<", xml.index("?>") + 2 if xml.startswith(
                "<?xml") else 0))
            assert "xmlns:" not in xml[root_end:], name


def test_gnumeric_imports_every_chart(needs, tmp_path):
    """Gnumeric itself (ssconvert) reads the book's charts: one graph object per chart."""
    import gzip
    import subprocess
    import zipfile
    needs("gnumeric")
    book, out = tmp_path / "fourbar.xlsx", tmp_path / "fourbar.gnumeric"
    builder.build_file(templates.load("fourbar"), book)
    subprocess.run(["ssconvert", str(book), str(out)], check=True, capture_output=True,
                   timeout=HANG_GUARD_S)
    with zipfile.ZipFile(book) as z:
        charts = sum(1 for n in z.namelist() if re.fullmatch(r"xl/charts/chart\d+\.xml", n))
    graphs = len(re.findall(r"<gnm:SheetObjectGraph\b", gzip.decompress(out.read_bytes())
                            .decode("utf-8", "replace")))
    assert charts and graphs == charts, (charts, graphs)
