"""Row recurrences (engine/scan.py): columns whose cells read earlier rows of each other, evaluated
as one pass down the rows. Their values must be those of the cell-by-cell path, bit for bit and
type for type, errors included; and those a hand computation and LibreOffice give."""
from __future__ import annotations

import math

import openpyxl
import pytest

from linkbook.engine import evaluator as engine
from linkbook.engine import office

# The number whose square root each row finds: slowly moving (a row's Newton starts from the
# row above's root and converges in two steps), a negative (no root: #N/A, and the next row
# starts again from 1), text (#VALUE!), and 1 exactly (root 1: 1/(root-1) is #DIV/0!).
RADICANDS = ([1.0] + [1.0 + 0.001 * k for k in range(1, 12)] + [-0.5, 1.02, 1.021, "x"]
             + [1.03 + 0.002 * k for k in range(8)] + [4, 1.0, 1.001])
TOLERANCE = 1e-4


def newton_book() -> openpyxl.Workbook:
    """Columns B-E: two Newton steps for the square root of A, from the row above's root (1 in
    the first row, whose row above is a header, and after a row without one); E the root where
    the last step moved it by at most TOLERANCE of itself, else #N/A. F a running sum written
    term first (no `above + term`), G a value carried down past the rows without a root."""
    wb = openpyxl.Workbook()
    ws = wb.active
    ws.title = "Roots"
    for col, head in zip("ABCDEFG", ["a", "x0", "x1", "x2", "root", "sum", "1/(root-1)"]):
        ws[f"{col}1"] = head
    ws["F1"] = 0
    for r, a in enumerate(RADICANDS, start=2):
        ws[f"A{r}"] = a
        ws[f"B{r}"] = f"=IF(ISNUMBER(E{r - 1}),E{r - 1},1)"
        ws[f"C{r}"] = f"=B{r}-(B{r}^2-A{r})/(2*B{r})"
        ws[f"D{r}"] = f"=C{r}-(C{r}^2-A{r})/(2*C{r})"
        ws[f"E{r}"] = f"=IF(ABS(D{r}-C{r})<={TOLERANCE}*ABS(D{r}),D{r},NA())"
        ws[f"F{r}"] = f"=IF(ISNUMBER(E{r}),E{r},0)+F{r - 1}"
        ws[f"G{r}"] = f"=IF(ISNUMBER(E{r}),1/(E{r}-1),G{r - 1})"
    return wb


def by_hand() -> dict[str, list]:
    """Each column's values, computed here with Python's floats in the formulas' order of
    operations (the operations the cells' arithmetic is); errors as their codes."""
    columns = {c: [] for c in "BCDEFG"}
    root, total, carried = "root", 0.0, "1/(root-1)"
    for a in RADICANDS:
        b = root if isinstance(root, float) else 1.0
        if isinstance(a, str):
            c = d = root = "#VALUE!"
        else:
            c = b - (b ** 2.0 - a) / (2.0 * b)
            d = c - (c ** 2.0 - a) / (2.0 * c)
            root = d if abs(d - c) <= TOLERANCE * abs(d) else "#N/A"
        total = (root if isinstance(root, float) else 0.0) + total
        if isinstance(root, float):
            carried = "#DIV/0!" if root == 1.0 else 1.0 / (root - 1.0)
        for col, value in zip("BCDEFG", (b, c, d, root, total, carried)):
            columns[col].append(value)
    return columns


def grid_values(e: engine.Engine, sheet: str) -> dict[tuple[int, int], object]:
    grid = e.grid[sheet]
    return {(g.sheet, m.row, m.col): grid[m.row, m.col] for g in e.groups for m in g.members
            if g.sheet == sheet}


def assert_same_cells(got: dict, want: dict) -> None:
    """Same keys; each value of the same type and bits (the sign of a zero), or the same error."""
    assert set(got) == set(want)
    for key, w in want.items():
        g = got[key]
        if engine.is_error(w) or engine.is_error(g):
            assert engine.error_code(g) == engine.error_code(w), (key, g, w)
        elif isinstance(w, float) and math.isnan(w):
            assert isinstance(g, float) and math.isnan(g), key
        else:
            assert type(g) is type(w) and g == w, (key, g, w)
            if isinstance(w, float) and w == 0:
                assert math.copysign(1, g) == math.copysign(1, w), key


@pytest.fixture(scope="module")
def scanned():
    wb = newton_book()
    e = engine.Engine(wb)
    return wb, e, e.run()


def test_a_newton_recurrence_is_scanned_to_the_values_computed_by_hand(scanned):
    _, e, values = scanned
    assert e.stats["scans"] == 3 and e.stats["cyclic_cells"] == 0   # B-E, F, G
    # the cell path only where a cell reads what is not a number: B2 (a header above), the
    # text row's C, D, the rows after it that read an error, NA() picked, 1/0
    assert e.stats["scan_cell_path"] < e.stats["scan_cells"] / 3
    want = by_hand()
    assert "#N/A" in want["E"] and "#VALUE!" in want["E"] and "#DIV/0!" in want["G"]
    for col, column in want.items():
        for r, w in enumerate(column, start=2):
            g = values[("Roots", f"{col}{r}")]
            if isinstance(w, str):
                assert engine.error_code(g) == w, (col, r, g)
            else:
                assert g == w, (col, r, g, w)


def test_the_scan_gives_what_the_cell_path_gives(scanned):
    wb, e, _ = scanned
    slow = engine.Engine(wb, scan=False)
    slow.run()
    assert slow.stats["scans"] == 0 and slow.stats["cyclic_cells"] > 0
    assert_same_cells(grid_values(e, "Roots"), grid_values(slow, "Roots"))


@pytest.mark.libreoffice
def test_libreoffice_recalculates_the_recurrence_to_the_scans_values(scanned, needs,
                                                                      tmp_path):
    needs("libreoffice")
    wb, _, values = scanned
    wb.save(tmp_path / "roots.xlsx")
    theirs = office.recalculated_values(tmp_path / "roots.xlsx")
    compared = 0
    for (sheet, cell), ours in values.items():
        if cell[0] not in "BCDEFG" or cell[1:] == "1":
            continue
        their = theirs[(sheet, cell)]
        if engine.is_error(ours):
            assert office_code(their) == engine.error_code(ours), (cell, their, ours)
        else:
            assert their == pytest.approx(ours, rel=1e-13, abs=1e-15), (cell, their, ours)
        compared += 1
    assert compared == 6 * len(RADICANDS)


def office_code(value) -> str | None:
    return str(value) if isinstance(value, str) else None


# ---------------------------------------------------------------- the fast forms, node by node

PANEL = [0.5, -0.5, 0.0, -0.0, 2.0, -3.7, 1e-300, 1e300, 7, -2, 0, True, "abc", None, "=NA()",
         "=1/0"]
SECOND = [0.5, -1, 0, 2, 3.7, -0.0, 1e300, True, "abc", None, "=NA()"]
EXPRESSIONS = [
    "A{r}+B{r}", "A{r}-B{r}", "A{r}*B{r}", "A{r}/B{r}", "A{r}^B{r}", "-A{r}", "A{r}%", "+A{r}",
    "A{r}=B{r}", "A{r}<>B{r}", "A{r}<B{r}", "A{r}>B{r}", "A{r}<=B{r}", "A{r}>=B{r}",
    "COS(A{r})*2", "SIN(A{r})", "TAN(A{r})", "ACOS(A{r})", "ASIN(A{r})", "ATAN(A{r})",
    "SQRT(A{r})", "EXP(A{r})", "LN(A{r})", "ABS(A{r})", "DEGREES(A{r})", "RADIANS(A{r})",
    "ATAN2(A{r},B{r})", "MOD(A{r},B{r})", "PI()*A{r}", "ISNUMBER(A{r})", "ISNUMBER(A{r}>B{r})",
    "IF(A{r}>B{r},A{r},B{r})", "IF(A{r},B{r})", "IF(A{r}>0,B{r},NA())", "IF(B{r},2,1.5)*A{r}",
    "(A{r}>B{r})*3", "A{r}+2*B{r}-1E-9/B{r}", "ATAN2(A{r},B{r})-MOD(A{r},B{r})*ABS(B{r})",
    "MAX(A{r},B{r})", 'A{r}&"t"',       # outside the fast form: the cell path, in the scan
]


def panel_book() -> openpyxl.Workbook:
    """Each expression over each pair of panel values, one column each, as
    IF(TRUE, expression, the cell above): every column a recurrence whose value is the
    expression's (IF evaluates the branch it picks)."""
    wb = openpyxl.Workbook()
    ws = wb.active
    pairs = [(a, b) for a in PANEL for b in SECOND]
    for r, (a, b) in enumerate(pairs, start=2):
        for col, v in ((1, a), (2, b)):
            if v is not None:
                ws.cell(row=r, column=col, value=v)
        for j, expression in enumerate(EXPRESSIONS):
            above = openpyxl.utils.get_column_letter(3 + j) + str(r - 1)
            ws.cell(row=r, column=3 + j,
                    value=f"=IF(TRUE,{expression.format(r=r)},{above})")
    return wb


def test_fast_forms_give_the_cell_paths_bits_and_types():
    """Numbers, ints, zeros of both signs, the largest and smallest, booleans, text, blanks and
    errors through every operation the fast form writes: each cell the value and type the
    cell path gives (the fast form gives way where it would differ)."""
    wb = panel_book()
    fast = engine.Engine(wb)
    fast.run()
    slow = engine.Engine(wb, scan=False)
    slow.run()
    assert fast.stats["scans"] == len(EXPRESSIONS)
    # the fast forms gave a third of the values (not text, blanks, errors, MAX, &)
    assert fast.stats["scan_cell_path"] < fast.stats["scan_cells"] * 2 / 3
    assert_same_cells(grid_values(fast, "Sheet"), grid_values(slow, "Sheet"))
    errors = sum(engine.is_error(v) for v in grid_values(slow, "Sheet").values())
    assert errors > len(EXPRESSIONS)        # the domain edges were reached


def test_what_is_no_row_recurrence_is_left_to_the_general_cycle_path():
    """A column reading the row below is no recurrence: a true cycle through it still raises.
    Two columns reading each other's rows above through a range are none either: split into
    cells as before, and the values agree."""
    wb = openpyxl.Workbook()
    ws = wb.active
    for r in range(1, 5):
        ws[f"A{r}"] = f"=A{r + 1}+1"
    ws["A5"] = "=A1"
    with pytest.raises(engine.CircularReferenceError):
        engine.evaluate(wb)
    wb = openpyxl.Workbook()
    ws = wb.active
    ws["A1"], ws["B1"] = 1.0, 2.0
    for r in range(2, 30):
        ws[f"A{r}"] = f"=SUM(B{r - 1}:B{r - 1})*0.5+1"
        ws[f"B{r}"] = f"=A{r}+A{r - 1}"
    fast = engine.Engine(wb)
    fast.run()
    slow = engine.Engine(wb, scan=False)
    slow.run()
    assert fast.stats["scans"] == 0 and fast.stats["split_groups"] > 0
    assert_same_cells(grid_values(fast, "Sheet"), grid_values(slow, "Sheet"))


def test_a_rerun_scans_again_with_the_other_inputs(scanned):
    """verify's other input sets: the recurrence moves with a changed input, as a fresh
    evaluation of the book holding it gives."""
    from linkbook.engine.rerun import rerun
    _, e, before = scanned
    with rerun(e, {("Roots", "A3"): 1.5}) as values:
        got = {key: values[key] for key in values if key[1][0] in "BCDEFG"}
    changed = newton_book()
    changed["Roots"]["A3"] = 1.5
    want = engine.Engine(changed, scan=False).run()
    assert_same_cells(got, {key: want[key] for key in got})
    assert got[("Roots", "E3")] != before[("Roots", "E3")]


# ---------------------------------------------------------------- one form for shifted copies

def shifted_copies_book() -> openpyxl.Workbook:
    """newton_book's root columns B-E twice more: shifted to I-L (radicands in H), and onto a
    second sheet four rows down in C-F (radicands in B). Each copy has a column carrying root ×
    a factor down past the rows without a root, the factor read with an absolute row ($P$1,
    $Q$1, and from the second sheet Roots!$R$1, where More!R1 is a decoy), and the second
    sheet has one more by a relative one (G6, G7, ...): one skeleton, two forms."""
    wb = newton_book()
    roots = wb["Roots"]
    more = wb.create_sheet("More")
    roots["P1"], roots["Q1"], roots["R1"], more["R1"] = 3.0, -0.5, 2.0, 7.0
    for r, a in enumerate(RADICANDS, start=2):
        roots[f"H{r}"] = a
        more[f"B{r + 4}"], more[f"G{r + 4}"] = a, 0.5 + 0.25 * r
    copies = ((roots, 0, "ABCDE", {"N": "$P$1"}), (roots, 0, "HIJKL", {"O": "$Q$1"}),
              (more, 4, "BCDEF", {"H": "Roots!$R$1", "I": "G{r}"}))
    for ws, down, (a, b, c, d, e), factors in copies:
        for k in range(len(RADICANDS)):
            r = k + 2 + down
            if b != "B":                # B-E are newton_book's own
                ws[f"{b}{r}"] = f"=IF(ISNUMBER({e}{r - 1}),{e}{r - 1},1)"
                ws[f"{c}{r}"] = f"={b}{r}-({b}{r}^2-{a}{r})/(2*{b}{r})"
                ws[f"{d}{r}"] = f"={c}{r}-({c}{r}^2-{a}{r})/(2*{c}{r})"
                ws[f"{e}{r}"] = (f"=IF(ABS({d}{r}-{c}{r})<={TOLERANCE}*ABS({d}{r}),"
                                 f"{d}{r},NA())")
            for carried, factor in factors.items():
                ws[f"{carried}{r}"] = (f"=IF(ISNUMBER({e}{r}),{e}{r}*{factor.format(r=r)},"
                                       f"{carried}{r - 1})")
    return wb


def test_shifted_copies_of_a_recurrence_share_forms_and_read_their_own_cells():
    """A form is written once for every copy of a formula (scan.py: the iteration blocks of a
    triad); each copy reads its own columns, rows and sheet: the roots by hand in every copy,
    every cell what the cell path gives, bit for bit."""
    from linkbook.engine import scan
    scan._FORMS.clear()
    wb = shifted_copies_book()
    fast = engine.Engine(wb)
    values = fast.run()
    # newton_book's 3 scans and 5 forms (B; C and D, one skeleton; E; F; G), 6 more scans
    # and 2 more forms: the carried columns' by an absolute and by a relative factor
    assert fast.stats["scans"] == 9 and len(scan._FORMS) == 7
    # the fast forms gave most values (a form reading a wrong row meets blanks: the cell path)
    assert fast.stats["scan_cell_path"] < fast.stats["scan_cells"] / 3
    slow = engine.Engine(wb, scan=False)
    slow.run()
    for sheet in ("Roots", "More"):
        assert_same_cells(grid_values(fast, sheet), grid_values(slow, sheet))
    want = by_hand()
    for sheet, down, columns in (("Roots", 0, "BCDE"), ("Roots", 0, "IJKL"),
                                 ("More", 4, "CDEF")):
        for col, mine in zip(columns, "BCDE"):
            for r, w in enumerate(want[mine], start=2 + down):
                g = values[(sheet, f"{col}{r}")]
                assert (engine.error_code(g) == w if isinstance(w, str) else g == w), \
                    (sheet, col, r, g, w)
    for sheet, down, col, column, factor in (("Roots", 0, "N", "E", 3.0),
                                             ("Roots", 0, "O", "L", -0.5),
                                             ("More", 4, "H", "F", 2.0)):
        last = None                                     # root × factor, carried down
        for r in range(2 + down, 2 + down + len(RADICANDS)):
            root = values[(sheet, f"{column}{r}")]
            if not engine.is_error(root):
                last = root * factor
            g = values[(sheet, f"{col}{r}")]
            assert (g == last if last is not None else engine.is_error(g)), (col, r, g, last)
