"""The Synthesis sheet (function generation, docs/synthesis.md): the textbook's steps as live
formulas. The task's inputs in named yellow cells; the precision points (Chebyshev's, equally
spaced or given) with the rows of Freudenstein's equation; the 3×3 system Cramer's rule solves
(the rows themselves for three points, the normal equations MᵀM·K = Mᵀr written out as sums
for more); its condition; K1, K2, K3 turned into the lengths; the residual, the branch and the
structural error at each point; Grashof's class, the transmission angle's range; and the
designed parameters' named cells, which every other sheet reads as it reads an input.

The checks' words are base.sheets.SYNTHESIS_WORDS, which verify reads too.
"""
from __future__ import annotations

from openpyxl.utils import get_column_letter

from ..base.sheets import DASH, SYNTHESIS, SYNTHESIS_WORDS as WORDS
from ..language.excel import acos_or_na, in_domain_or_na, render
from ..language.model import DEG, LENGTH, RAD, RATIO, Model
from ..language.synthesis import DEAD_CENTRE, SINGULAR_COND, FunctionTask
from ..language.templates import Template
from .resolve import Resolver
from .style import (BOLD, BOX, DERIVED_FILL, INPUT_FILL, NOTE, TITLE, block_head, column_width,
                    define_name, fit_heads, number_format, put_head, put_text, set_formula,
                    unit_text)
from .summary import grashof_formula
from .synthesis_drawing import joints_at, positions_drawing

ERROR_STEPS = 40          # intervals of the structural-error table over the input range
TABLE_COLUMN = 7          # the tables start in column G, right of the task and its solution
HEAD_HEIGHT = 30.0        # points: a table's headers in up to two lines
FREUDENSTEIN = ("Freudenstein's equation (Norton's form): K1·cos θ4 − K2·cos θ2 + K3 = "
                "cos(θ2 − θ4), with K1 = d/a, K2 = d/c, K3 = (a² − b² + c² + d²)/(2ac).")
CONVENTION = ("A0 at the origin, B0 at (d, 0); θ2 = angle of A0→A, θ4 = angle of B0→B, both "
              "from +x counter-clockwise. Sources differ: some put the ground at 180°.")
TASK_INPUTS = (("x0", "start of x", "x0", RATIO), ("x1", "end of x", "x1", RATIO),
               ("theta2_start", "crank angle at x0", "θ2s", DEG),
               ("theta2_span", "crank's signed span over [x0, x1]", "Δθ2", DEG),
               ("theta4_start", "rocker angle at f(x0)", "θ4s", DEG),
               ("theta4_span", "rocker's signed span over [f(x0), f(x1)]", "Δθ4", DEG))
# the precision-point table's columns: key, header
POINT_COLUMNS = (("j", "j"), ("x", "x_j"), ("y", "y_j = f(x_j)"), ("theta2_deg", "θ2_j [deg]"),
                 ("theta4_deg", "θ4_j [deg]"), ("theta2", "θ2_j [rad]"),
                 ("theta4", "θ4_j [rad]"), ("m1", "cos θ4_j"), ("m2", "−cos θ2_j"),
                 ("m3", "1 (× K3)"), ("r", "cos(θ2_j − θ4_j)"), ("residual", "residual"),
                 ("cross", "cross(B−B0, A−B0)"), ("branch", "branch"),
                 ("generated", "θ4 by the steps [rad]"),
                 ("error", "structural error [deg]"),
                 ("m11", "cos²θ4"), ("m12", "cos θ4·(−cos θ2)"), ("m13", "cos θ4·1"),
                 ("m22", "cos²θ2"), ("m23", "−cos θ2·1"), ("m33", "1·1"),
                 ("v1", "cos θ4·r"), ("v2", "−cos θ2·r"), ("v3", "1·r"))
ERROR_COLUMNS = (("k", "k"), ("x", "x"), ("theta2_deg", "θ2 [deg]"), ("y", "y = f(x)"),
                 ("desired", "θ4 desired [deg]"), ("generated", "θ4 by the steps [rad]"),
                 ("error", "structural error [deg]"))


class _Block:
    """A column of labelled cells (quantity, symbol, value, unit, Excel name) from `row` on,
    each recorded under its key."""

    def __init__(self, wb, ws, t: Template, row: int):
        self.wb, self.ws, self.t, self.row = wb, ws, t, row
        self.cells: dict[str, str] = {}

    def add(self, key: str, label: str, symbol: str, value, unit: str, *, name: str = "",
            given: bool = False, text: bool = False) -> str:
        r, ws = self.row, self.ws
        put_text(ws, f"A{r}", label)
        put_text(ws, f"B{r}", symbol)
        cell = ws[f"C{r}"]
        if given:
            cell.value = value
            cell.fill, cell.border = INPUT_FILL, BOX
        elif isinstance(value, str) and value.startswith("="):
            set_formula(cell, value)
            cell.fill = DERIVED_FILL
        elif text:
            put_text(ws, f"C{r}", value)
        else:
            cell.value = value
        if unit and not text:
            cell.number_format = number_format(unit, self.t.length_unit)
            put_text(ws, f"D{r}", unit_text(unit, self.t.length_unit))
        if name:
            put_text(ws, f"E{r}", name, NOTE)
            define_name(self.wb, name, SYNTHESIS, f"C{r}")
        self.cells[key] = f"C{r}"
        self.row += 1
        return f"C{r}"

    def title(self, text: str) -> None:
        self.row += 1
        self.ws[f"A{self.row}"] = text
        self.ws[f"A{self.row}"].font = BOLD
        self.row += 1


def _letters(cell: str) -> str:
    return cell.rstrip("0123456789")


def _det3(m: list[list[str]]) -> str:
    """The determinant of the 3×3 matrix of cells `m`, by the first row."""
    return (f"{m[0][0]}*({m[1][1]}*{m[2][2]}-{m[1][2]}*{m[2][1]})"
            f"-{m[0][1]}*({m[1][0]}*{m[2][2]}-{m[1][2]}*{m[2][0]})"
            f"+{m[0][2]}*({m[1][0]}*{m[2][1]}-{m[1][1]}*{m[2][0]})")


def synthesis_sheet(wb, ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The sheet, and its record: the task's input cells, every result's cell by key, the
    precision points' and the structural error's columns."""
    task = t.synthesis
    put_text(ws, "A1", f"Synthesis: function generation, y = {task.f}", TITLE)
    put_text(ws, "A2", FREUDENSTEIN, NOTE)
    put_text(ws, "A3", CONVENTION, NOTE)
    put_text(ws, "A4", "Yellow cells are the task's inputs: change them and the design, and "
                       "every sheet that analyses it, follow. #N/A: the design does not exist.",
             NOTE)
    block_head(ws, "A", "Task", (("Quantity", 44), ("Symbol", 10), ("Value", 14), ("Unit", 8),
                                 ("Excel name", 16)), row=6)
    b = _Block(wb, ws, t, 8)
    b.add("f", "the function to generate", "y = f(x)", task.f, "", text=True)
    inputs = {}
    for (key, label, symbol, unit), value in zip(TASK_INPUTS, (*task.x, *task.theta2,
                                                               *task.theta4)):
        inputs[key] = b.add(key, label, symbol, value, unit, name=f"syn_{key}", given=True)
    n = task.points
    b.add("points", "precision points (3 exact; more: least squares)", "n", n, "", text=False)
    b.add("spacing", "their spacing", "", task.spacing, "", text=True)
    d = b.add("d", "ground link |A0B0| (an input on sheet Mechanism)", "d",
              f"={names[task.ground]}", LENGTH, name="syn_d")
    fx = lambda x: render(task.f_excel, lambda _: x)          # noqa: E731  f of a cell
    fx0 = b.add("f_x0", "f(x0)", "f(x0)", f"={fx('syn_x0')}", RATIO)
    fx1 = b.add("f_x1", "f(x1)", "f(x1)", f"={fx('syn_x1')}", RATIO)
    columns, sums, given = _points_table(ws, t, model, names, 7, fx, fx0, fx1, d)
    inputs.update(given)
    b.row += 1
    # the error table's headers level with the solution's title: a tall row there is no gap
    head = max(int(sums["m11"][len(_letters(sums["m11"])):]) + 4, b.row + 1)
    _solution(b, task, columns, sums, d)
    cells = {**b.cells, **{f"sum_{key}": cell for key, cell in sums.items()}}
    error = _error_table(ws, t, model, names, head, fx, fx0, fx1)
    cells.update(error.pop("cells"))
    drawing_head = error.pop("rows")[1] + 3
    drawing = _drawing(ws, t, model, names, drawing_head, columns["theta2_deg"])
    _fit(ws, head, drawing_head)
    ws.freeze_panes = "A7"
    return {"sheet": SYNTHESIS, "inputs": inputs, "cells": cells,
            "points": {k: tuple(v) for k, v in columns.items()
                       if k not in ("j", "m3") and not (k == "x" and given)},
            "error": {k: tuple(v) for k, v in error.items() if k != "k"},
            "drawing": drawing,
            "task": {"kind": "function", "f": task.f, "spacing": task.spacing, "points": n,
                     "ground": task.ground, "designs": dict(task.designs),
                     "output": task.output}}


def _drawing(ws, t: Template, model: Model, names: dict[str, str], head: int,
             angles: list[str]) -> dict:
    """The designed linkage at each precision point's θ2_j by the position steps, and the
    live frame of its drawing (synthesis_drawing.py), under the structural error's table."""
    first = get_column_letter(TABLE_COLUMN)
    ws[f"{first}{head - 1}"] = ("The designed linkage at each precision position (the position "
                                "steps at θ2_j), drawn to scale")
    ws[f"{first}{head - 1}"].font = BOLD
    positions = joints_at(ws, t, model, names, head, TABLE_COLUMN, angles)
    return positions_drawing(ws, t, positions, head, TABLE_COLUMN + 6)


def _fit(ws, *heads: int) -> None:
    """Column A as wide as its longest label (the block's quantities), and the headers of the
    tables (the precision points', and those in rows `heads`) whole: no label clipped on
    screen or on paper."""
    labels = [c.value for (c,) in ws.iter_rows(min_row=8, min_col=1, max_col=1)
              if isinstance(c.value, str) and not c.font.b]
    ws.column_dimensions["A"].width = max([ws.column_dimensions["A"].width or 12] +
                                          [column_width(text) for text in labels])
    for row in (7, *heads):
        fit_heads(ws, row, [get_column_letter(c) for c in range(TABLE_COLUMN, ws.max_column + 1)
                            if isinstance(ws.cell(row, c).value, str)])


def _table_head(ws, head: int, title: str, columns, height: float | None = HEAD_HEIGHT
                ) -> dict[str, str]:
    """A table's bold title above row `head` and its headers in it, from TABLE_COLUMN on; the
    column letter of each key. `height`: the header row's, or None to leave it to fit_heads."""
    first = get_column_letter(TABLE_COLUMN)
    ws[f"{first}{head - 1}"] = title
    ws[f"{first}{head - 1}"].font = BOLD
    if height is not None:
        ws.row_dimensions[head].height = height
    letter = {}
    for i, (key, text) in enumerate(columns, start=TABLE_COLUMN):
        put_head(ws, head, i, text)
        letter[key] = get_column_letter(i)
    return letter


def _points_table(ws, t, model, names, head, fx, fx0, fx1, d):
    """The precision-point table from row `head`: its columns' cells by key, the sums row's
    cells by key (the normal equations' entries) and the given x values' input cells."""
    task = t.synthesis
    n = task.points
    letter = _table_head(ws, head, "Precision points and the rows of Freudenstein's equation",
                         POINT_COLUMNS)
    for key, column in letter.items():
        ws.column_dimensions[column].width = 5 if key == "j" else 13
    first = head + 1
    columns: dict[str, list[str]] = {key: [] for key, _ in POINT_COLUMNS}
    given: dict[str, str] = {}
    cramer = {"a": "syn_a", "c": "syn_c", "K1": "syn_K1", "K2": "syn_K2", "K3": "syn_K3"}
    for j in range(1, n + 1):
        r = first + j - 1
        c = {key: f"{letter[key]}{r}" for key in letter}
        x_formula = {"chebyshev": f"=(syn_x0+syn_x1)/2-(syn_x1-syn_x0)/2"
                                  f"*COS((2*{c['j']}-1)*PI()/(2*{n}))",
                     "equal": f"=syn_x0+({c['j']}-1)*(syn_x1-syn_x0)/({n}-1)"}
        theta = f"RADIANS({c['theta2_deg']})"
        # the position steps with this row's crank angle as their input: the designed linkage
        steps = Resolver(model, names, {t.mechanism.input_column: c["theta2_deg"]})
        formulas = {
            "y": f"={fx(c['x'])}",
            "theta2_deg": f"=syn_theta2_start+({c['x']}-syn_x0)/(syn_x1-syn_x0)*syn_theta2_span",
            "theta4_deg": f"=syn_theta4_start+({c['y']}-{fx0})/({fx1}-{fx0})*syn_theta4_span",
            "theta2": f"={theta}", "theta4": f"=RADIANS({c['theta4_deg']})",
            "m1": f"=COS({c['theta4']})", "m2": f"=-COS({c['theta2']})",
            "r": f"=COS({c['theta2']}-{c['theta4']})",
            "residual": f"={c['m1']}*{cramer['K1']}+{c['m2']}*{cramer['K2']}"
                        f"+{c['m3']}*{cramer['K3']}-{c['r']}",
            "cross": f"={cramer['c']}*COS({c['theta4']})*{cramer['a']}*SIN({c['theta2']})"
                     f"-{cramer['c']}*SIN({c['theta4']})*({cramer['a']}*COS({c['theta2']})"
                     f"-{d})",
            "branch": f"=IF(ABS({c['cross']})<={DEAD_CENTRE:G}*ABS({cramer['c']})"
                      f"*SQRT(({cramer['a']}*COS({c['theta2']})-{d})^2"
                      f"+({cramer['a']}*SIN({c['theta2']}))^2),0,SIGN({c['cross']}))",
            "generated": steps.formula(task.output),
            "error": f"=MOD(DEGREES({c['generated']})-{c['theta4_deg']}+180,360)-180",
        }
        for key, (p, q) in {"m11": ("m1", "m1"), "m12": ("m1", "m2"), "m13": ("m1", "m3"),
                            "m22": ("m2", "m2"), "m23": ("m2", "m3"), "m33": ("m3", "m3"),
                            "v1": ("m1", "r"), "v2": ("m2", "r"), "v3": ("m3", "r")}.items():
            formulas[key] = f"={c[p]}*{c[q]}"
        ws[c["j"]] = j
        ws[c["m3"]] = 1
        if task.spacing == "given":
            ws[c["x"]] = task.given[j - 1]
            ws[c["x"]].fill, ws[c["x"]].border = INPUT_FILL, BOX
            given[f"x_{j}"] = c["x"]
        else:
            set_formula(ws[c["x"]], x_formula[task.spacing])
        for key, text in formulas.items():
            set_formula(ws[c[key]], text)
        for key, cell in c.items():
            columns[key].append(cell)
            if key not in ("j", "branch"):
                ws[cell].number_format = number_format(
                    DEG if key.endswith(("deg", "error")) else RAD if key.startswith("theta")
                    else RATIO)
    last = first + n - 1
    sums = {}
    put_text(ws, f"{get_column_letter(TABLE_COLUMN)}{last + 1}", "Σ", BOLD)
    for key in ("m11", "m12", "m13", "m22", "m23", "m33", "v1", "v2", "v3"):
        cell = f"{letter[key]}{last + 1}"
        set_formula(ws[cell], f"=SUM({letter[key]}{first}:{letter[key]}{last})")
        ws[cell].number_format = number_format(RATIO)
        sums[key] = cell
    return columns, sums, given


def _solution(b: _Block, task: FunctionTask, columns, sums, d: str) -> None:
    """The system, its condition, Cramer's rule, the lengths, the checks in words and the
    designed parameters' named cells."""
    n = task.points
    if n == 3:
        b.title("The system M·K = r: the three rows of the table, solved by Cramer's rule")
        rows = [[columns[k][i] for k in ("m1", "m2", "m3", "r")] for i in range(3)]
    else:
        b.title(f"Least squares: the normal equations MᵀM·K = Mᵀr (the Σ row), solved by "
                f"Cramer's rule")
        s = sums
        rows = [[s["m11"], s["m12"], s["m13"], s["v1"]], [s["m12"], s["m22"], s["m23"], s["v2"]],
                [s["m13"], s["m23"], s["m33"], s["v3"]]]
    system = _matrix(b, rows)
    # the condition of the rows [cos θ4, −cos θ2, 1]: the eigenvalues of MᵀM (the Σ row), a
    # symmetric 3×3, by the trigonometric formula
    s = sums
    q = b.add("eig_mean", "trace(MᵀM)/3", "q", f"=({s['m11']}+{s['m22']}+{s['m33']})/3", RATIO)
    spread = (f"(({s['m11']}-{q})^2+({s['m22']}-{q})^2+({s['m33']}-{q})^2"
              f"+2*({s['m12']}^2+{s['m13']}^2+{s['m23']}^2))/6")
    p = b.add("eig_p", "spread of MᵀM's eigenvalues", "p",
              f"={in_domain_or_na('SQRT', spread)}", RATIO)
    shifted = [[f"({s['m11']}-{q})", s["m12"], s["m13"]], [s["m12"], f"({s['m22']}-{q})",
               s["m23"]], [s["m13"], s["m23"], f"({s['m33']}-{q})"]]
    half = b.add("eig_r", "det((MᵀM − q·I)/p)/2", "ρ", f"=({_det3(shifted)})/{p}^3/2", RATIO)
    # ρ lies in [−1, 1]; rounding can put it a hair beyond, where the formula means ±1
    phi = b.add("eig_phi", "ACOS(ρ)/3", "φ", f"={acos_or_na(f'MAX(-1,MIN(1,{half}))')}/3", RAD)
    big = b.add("eig_max", "largest eigenvalue of MᵀM", "λmax", f"={q}+2*{p}*COS({phi})", RATIO)
    small = b.add("eig_min", "smallest eigenvalue of MᵀM", "λmin",
                  f"={q}+2*{p}*COS({phi}+2*PI()/3)", RATIO)
    b.add("condition", "condition number cond₂(M) = √(λmax/λmin)", "cond₂",
          f"=IF({small}>0,{in_domain_or_na('SQRT', f'{big}/{small}')},NA())", RATIO)
    singular = f"{big}>{SINGULAR_COND ** 2:G}*{small}"
    b.add("system", "the system", "", f'=IF({singular},"{WORDS["singular"]}",'
                                      f'"{WORDS["solvable"]}")', "")
    m = [row[:3] for row in system]
    rhs = [row[3] for row in system]
    det = b.add("D", "determinant of the system", "D", f"={_det3(m)}", RATIO)
    for k in range(3):
        replaced = [[rhs[i] if col == k else m[i][col] for col in range(3)] for i in range(3)]
        dk = b.add(f"D{k + 1}", f"D with column {k + 1} replaced by the right-hand side",
                   f"D{k + 1}", f"={_det3(replaced)}", RATIO)
        b.add(f"K{k + 1}", f"K{k + 1} = D{k + 1}/D (#N/A where near-singular)", f"K{k + 1}",
              f"=IF({singular},NA(),{dk}/{det})", RATIO, name=f"syn_K{k + 1}")
    a = b.add("a", "crank a = d/K1 (signed)", "a", "=IF(syn_K1=0,NA(),syn_d/syn_K1)", LENGTH,
              name="syn_a")
    c = b.add("c", "rocker c = d/K2 (signed)", "c", "=IF(syn_K2=0,NA(),syn_d/syn_K2)", LENGTH,
              name="syn_c")
    b2 = b.add("b2", "b² = a² + c² + d² − 2ac·K3", "b²", f"={a}^2+{c}^2+{d}^2-2*{a}*{c}*syn_K3",
               "length²")
    coupler = b.add("b", "coupler b = √b²", "b", f"=IF({b2}<0,NA(),SQRT({b2}))", LENGTH)
    b.add("lengths", "the crank and the rocker",
          "", f'=IF({a}>0,IF({c}>0,"{WORDS["positive"]}","{WORDS["rocker negative"]}"),'
              f'IF({c}>0,"{WORDS["crank negative"]}","{WORDS["both negative"]}"))', "")
    branches = f"{columns['branch'][0]}:{columns['branch'][-1]}"
    b.add("defect", "the branch at the precision points", "",
          f'=IF(AND(MAX({branches})=1,MIN({branches})=-1),"{WORDS["defect"]}",'
          f'"{WORDS["no defect"]}")', "")
    branch = b.add("branch", "their common branch (1 open, −1 crossed)", "",
                   f"=IF(MAX({branches})=1,IF(MIN({branches})=-1,NA(),1),"
                   f"IF(MIN({branches})=-1,-1,NA()))", "")
    b.add("grashof", "Grashof class of the designed linkage", "",
          "=" + grashof_formula(d, f"ABS({a})", coupler, f"ABS({c})"), "")
    for key, label, pick in (("mu_min", "smallest transmission angle over the input range",
                              "MIN"), ("mu_max", "largest transmission angle over the input "
                                                 "range", "MAX")):
        b.add(key, label, "μ", f"={pick}({_mu(a, coupler, c, d, 'cos_max')},"
                                 f"{_mu(a, coupler, c, d, 'cos_min')})", DEG)
    b.title("The designed parameters: every other sheet reads these named cells")
    usable = b.add("usable", "a linkage to analyse (a > 0, c > 0, b real, one branch)", "",
                   f"=AND({a}>0,{c}>0,{coupler}>0,ABS({branch})=1)", "")
    values = {"crank": a, "coupler": coupler, "rocker": c, "branch": branch}
    for role, symbol in task.designs:
        p = b.t.parameter(symbol)
        b.add(f"designed_{role}", f"{p.label} (designed)", symbol,
              f"=IF({usable},{values[role]},NA())", "" if role == "branch" else LENGTH,
              name=p.name)


def _matrix(b: _Block, rows: list[list[str]]) -> list[list[str]]:
    """The system as a 3×4 matrix of links (the coefficients of K1, K2, K3, the right-hand
    side), one row of the sheet per equation; its cells by row."""
    for k, text in enumerate(("× K1", "× K2", "× K3", "r"), start=2):
        put_head(b.ws, b.row, k, text)
    b.row += 1
    out = []
    for i, row in enumerate(rows, start=1):
        put_text(b.ws, f"A{b.row}", f"equation {i}")
        out.append([])
        for k, source in enumerate(row, start=1):
            cell = f"{get_column_letter(k + 1)}{b.row}"
            set_formula(b.ws[cell], f"={source}")
            b.ws[cell].fill = DERIVED_FILL
            b.ws[cell].number_format = number_format(RATIO)
            b.cells[f"S{i}{k}"] = cell
            out[-1].append(cell)
        b.row += 1
    return out


def _mu(a: str, b: str, c: str, d: str, which: str) -> str:
    """The transmission angle in degrees where cos θ2 is at its largest or smallest over the
    input range (a multiple of 2π, or of π, inside it; else the nearer end): μ is monotone in
    |A − B0|, and that in cos θ2."""
    lo = "RADIANS(MIN(syn_theta2_start,syn_theta2_start+syn_theta2_span))"
    hi = "RADIANS(MAX(syn_theta2_start,syn_theta2_start+syn_theta2_span))"
    ends = f"COS({lo}),COS({hi})"
    if which == "cos_max":
        cos = f"IF(INT({hi}/(2*PI()))>=-INT(-{lo}/(2*PI())),1,MAX({ends}))"
    else:
        cos = f"IF(INT(({hi}-PI())/(2*PI()))>=-INT(-({lo}-PI())/(2*PI())),-1,MIN({ends}))"
    arg = f"({b}^2+{c}^2-({a}^2+{d}^2-2*{a}*{d}*{cos}))/(2*{b}*ABS({c}))"
    return f"DEGREES({acos_or_na(arg)})"


def _error_table(ws, t, model, names, head, fx, fx0, fx1) -> dict:
    """The structural error over the input range: the rocker's angle the position steps give
    (the designed linkage, as every sheet analyses it) against the desired one; the largest
    error and where."""
    task = t.synthesis
    letter = _table_head(ws, head, f"Structural error over the input range ({ERROR_STEPS + 1} "
                                   "values of x): the designed linkage against the desired "
                                   "y = f(x)", ERROR_COLUMNS)
    out: dict = {key: [] for key, _ in ERROR_COLUMNS}
    for k in range(ERROR_STEPS + 1):
        r = head + 1 + k
        c = {key: f"{letter[key]}{r}" for key in letter}
        steps = Resolver(model, names, {t.mechanism.input_column: c["theta2_deg"]})
        ws[c["k"]] = k
        for key, text in {
                "x": f"=syn_x0+{c['k']}*(syn_x1-syn_x0)/{ERROR_STEPS}",
                "theta2_deg": f"=syn_theta2_start+{c['k']}*syn_theta2_span/{ERROR_STEPS}",
                "y": f"={fx(c['x'])}",
                "desired": f"=syn_theta4_start+({c['y']}-{fx0})/({fx1}-{fx0})*syn_theta4_span",
                "generated": steps.formula(task.output),
                "error": f"=MOD(DEGREES({c['generated']})-{c['desired']}+180,360)-180"}.items():
            set_formula(ws[c[key]], text)
            ws[c[key]].number_format = number_format(
                DEG if key in ("theta2_deg", "desired", "error") else
                RAD if key == "generated" else RATIO)
        for key, cell in c.items():
            out[key].append(cell)
    first, last = head + 1, head + 1 + ERROR_STEPS
    errors = f"{letter['error']}{first}:{letter['error']}{last}"
    label, value = (get_column_letter(TABLE_COLUMN + len(ERROR_COLUMNS) + k) for k in (1, 4))
    r = head + 1
    largest, where = f"{value}{r}", f"{value}{r + 1}"
    # x where |error| is the largest, else a dash: MIN skips the dashes and takes the first
    # such x (x grows down the table)
    at = get_column_letter(TABLE_COLUMN + len(ERROR_COLUMNS))
    put_head(ws, head, TABLE_COLUMN + len(ERROR_COLUMNS), "x at the largest |error|")
    for row, (x, e) in enumerate(zip(out["x"], out["error"]), start=first):
        set_formula(ws[f"{at}{row}"], f'=IF(ABS({e})={largest},{x},"{DASH}")')
        ws[f"{at}{row}"].number_format = number_format(RATIO)
        out.setdefault("at_largest", []).append(f"{at}{row}")
    at_largest = f"{at}{first}:{at}{last}"
    put_text(ws, f"{label}{r}", "largest |structural error| [deg]", BOLD)
    set_formula(ws[largest], f"=MAX(MAX({errors}),-MIN({errors}))")
    put_text(ws, f"{label}{r + 1}", "at x", BOLD)
    set_formula(ws[where], f"=MIN({at_largest})")
    ws[largest].number_format = number_format(DEG)
    ws[where].number_format = number_format(RATIO)
    ws[largest].fill = ws[where].fill = DERIVED_FILL
    out["cells"] = {"largest_error": largest, "largest_error_x": where}
    out["rows"] = (first, last)
    return out
