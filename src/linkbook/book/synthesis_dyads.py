"""The Synthesis sheet of motion generation and path generation with prescribed timing
(docs/synthesis.md, "For the sheet"): the textbook's standard dyad form as live formulas. The
task's three positions and rotations in named yellow cells; per dyad the coefficients
B_j = e^{iβ_j} − 1 and C_j = e^{iα_j} − 1 in real and imaginary parts, the determinant D,
Cramer's rule for W and Z (U and S), the condition cond₂; the pivots, the link lengths, the
coupler point and its offset; the designed linkage placed by the position steps at each pose
against the pose; the checks in words; and the designed parameters' named cells, which every
other sheet reads as it reads an input.

The checks' words are base.sheets.SYNTHESIS_WORDS, which verify reads too.
"""
from __future__ import annotations

from openpyxl.utils import get_column_letter

from ..base.sheets import SYNTHESIS, SYNTHESIS_WORDS as WORDS
from ..language.excel import acos_or_na, in_domain_or_na
from ..language.model import DEG, LENGTH, RATIO, Model
from ..language.synthesis_dyads import DEAD_CENTRE, DEGENERATE, SINGULAR_COND, DyadTask
from ..language.templates import Template
from .resolve import Resolver
from .style import (BOLD, NOTE, TITLE, block_head, column_width, fit_heads, number_format,
                    put_head, put_text, set_formula)
from .summary import grashof_formula
from .synthesis_drawing import joints_at, positions_drawing
from .synthesis import TABLE_COLUMN, _Block, _table_head

FORM = ("The standard dyad form (Norton §5.7): W·(e^{iβ_j} − 1) + Z·(e^{iα_j} − 1) = δ_j, "
        "j = 2, 3, for the crank's dyad; U and S with γ_j for the rocker's. In real and "
        "imaginary parts:",
        "W_x(cos β_j − 1) − W_y sin β_j + Z_x(cos α_j − 1) − Z_y sin α_j = δ_jx;  "
        "W_x sin β_j + W_y(cos β_j − 1) + Z_x sin α_j + Z_y(cos α_j − 1) = δ_jy.")
CONVENTION = ("At pose 1: W = A − A0, Z = P − A, U = B − B0, S = P − B; δ_j = P_j − P_1; "
              "α_j, β_j, γ_j are rotations from pose 1. cos ρ − 1 is written −2·sin²(ρ/2): "
              "the same number, without cancellation.")
TITLES = {"motion": "Synthesis: motion generation, three poses of the coupler",
          "path": "Synthesis: path generation with prescribed timing, three points"}
# the pose table's columns: key, header
POSE_COLUMNS = (("j", "j"), ("turn", "α_j − α_1 [deg]"), ("beta", "β_j [deg]"),
                ("gamma", "γ_j [deg]"), ("dx", "δ_jx"), ("dy", "δ_jy"),
                ("b_re", "cos β_j − 1"), ("b_im", "sin β_j"), ("c_re", "cos α_j − 1"),
                ("c_im", "sin α_j"), ("g_re", "cos γ_j − 1"), ("g_im", "sin γ_j"))
# the designed linkage at each pose: key, header
AT_POSE_COLUMNS = (("j", "j"), ("theta2", "θ2_j = ∠W + β_j [deg]"),
                   ("theta4", "θ4_j = ∠U + γ_j [deg]"), ("cross", "cross(B_j−B0, A_j−B0)"),
                   ("branch", "branch"), ("mu", "transmission angle μ_j [deg]"),
                   ("x", "x of P by the steps"), ("y", "y of P by the steps"),
                   ("angle", "coupler angle by the steps [deg]"), ("miss_x", "x − x_j"),
                   ("miss_y", "y − y_j"), ("miss_angle", "angle − α_j [deg]"))
LENGTH_KEYS = ("dx", "dy", "cross", "x", "y", "miss_x", "miss_y")
PIVOTS = {"crank": "A0", "rocker": "B0"}


def dyads_sheet(wb, ws, t: Template, model: Model, names: dict[str, str]) -> dict:
    """The sheet, and its record: the task's input cells, every result's cell by key, the
    pose tables' columns."""
    task: DyadTask = t.synthesis
    put_text(ws, "A1", TITLES[task.kind], TITLE)
    put_text(ws, "A2", FORM[0], NOTE)
    put_text(ws, "A3", FORM[1], NOTE)
    put_text(ws, "A4", CONVENTION, NOTE)
    put_text(ws, "A5", "Yellow cells are the task's inputs and free choices: change them and "
                       "the design, and every sheet that analyses it, follow. #N/A: the design "
                       "does not exist.", NOTE)
    block_head(ws, "A", "Task", (("Quantity", 44), ("Symbol", 10), ("Value", 14), ("Unit", 8),
                                 ("Excel name", 16)), row=6)
    b = _Block(wb, ws, t, 8)
    inputs = _task(b, task)
    head = 7
    poses = _pose_table(ws, head)
    b.row += 1
    # the second table's headers level with the crank's dyad's title: a tall row there is no
    # gap in the block
    at_head = b.row + 1
    for dyad, turn in (("crank", ("b_re", "b_im")), ("rocker", ("g_re", "g_im"))):
        if task.pivot(dyad) is None:
            _dyad(b, dyad, poses, turn)
        else:
            _dyad_about_pivot(b, dyad, poses)
    _four_bar(b)
    at_pose = _at_pose_table(ws, t, model, names, at_head)
    _checks(b, at_pose)
    _designed(b, task)
    _misses(ws, b, at_pose, at_head)
    drawing_head = at_head + 7
    drawing = _drawing(ws, t, model, names, drawing_head, at_pose["theta2"])
    _fit(ws, (head, at_head, drawing_head))
    ws.freeze_panes = "A7"
    columns = {**{f"pose_{k}": v for k, v in poses.items() if k != "j"},
               **{f"at_{k}": v for k, v in at_pose.items() if k != "j"}}
    return {"sheet": SYNTHESIS, "inputs": inputs, "cells": b.cells,
            "points": {k: tuple(v) for k, v in columns.items()}, "error": {},
            "drawing": drawing,
            "task": {"kind": task.kind, "designs": dict(task.designs),
                     "keys": dict(task.keys)}}


def _task(b: _Block, task: DyadTask) -> dict[str, str]:
    """The task's input cells, named syn_x1 … syn_gamma3; a path's α_1 is 0, not an input."""
    inputs = {}
    path = task.kind == "path"
    for j in range(1, 4):
        for key, what, value in (("x", "x", task.x[j - 1]), ("y", "y", task.y[j - 1])):
            inputs[f"{key}{j}"] = b.add(f"{key}{j}", f"{'point' if path else 'pose'} {j}: "
                                        f"{what} of the coupler point", f"{key}_{j}", value,
                                        LENGTH, name=f"syn_{key}{j}", given=True)
        if j == 1 and path:
            b.add("alpha1", "coupler angle at point 1 (the reference of α_j)", "α_1", 0.0, DEG,
                  name="syn_alpha1")
        elif not path:
            inputs[f"alpha{j}"] = b.add(f"alpha{j}", f"pose {j}: coupler angle", f"α_{j}",
                                        task.alpha[j - 1], DEG, name=f"syn_alpha{j}",
                                        given=True)
    rotations = [("beta", "crank", task.beta, "the task" if path else "free choice")]
    if path:
        rotations.append(("alpha", "coupler", task.alpha[1:], "free choice"))
    rotations.append(("gamma", "rocker", task.gamma, "free choice"))
    for dyad, pivot in task.pivots:
        for axis, value in zip("xy", pivot):
            inputs[f"{dyad}_{axis}"] = b.add(
                f"{dyad}_{axis}", f"given: the {dyad}'s fixed pivot {PIVOTS[dyad]}, {axis}",
                f"{axis}_{PIVOTS[dyad]}", value, LENGTH, name=f"syn_{dyad}_{axis}", given=True)
    for key, link, values, what in (r for r in rotations if r[2] is not None):
        for j, value in zip((2, 3), values):
            inputs[f"{key}{j}"] = b.add(f"{key}{j}", f"{what}: the {link}'s rotation from "
                                        f"{'point' if path else 'pose'} 1 to {j}",
                                        f"{dict(beta='β', alpha='α', gamma='γ')[key]}_{j}",
                                        value, DEG, name=f"syn_{key}{j}", given=True)
    return inputs


def _head(ws, head: int, title: str, columns) -> dict[str, str]:
    """synthesis.py's table head, its header row left to _fit, its columns 12 wide (j: 5)."""
    letter = _table_head(ws, head, title, columns, height=None)
    for key, column in letter.items():
        ws.column_dimensions[column].width = 5 if key == "j" else 12
    return letter


def _pose_table(ws, head: int) -> dict[str, list[str]]:
    """The rotations from pose 1, δ_j and the coefficients B_j, C_j (and the rocker's
    e^{iγ_j} − 1) in real and imaginary parts, rows j = 1, 2, 3."""
    letter = _head(ws, head, "The poses: rotations from pose 1, δ_j and the coefficients "
                             "e^{iρ} − 1 of the standard form", POSE_COLUMNS)
    out: dict[str, list[str]] = {key: [] for key, _ in POSE_COLUMNS}
    for j in range(1, 4):
        r = head + j
        c = {key: f"{letter[key]}{r}" for key in letter}
        ws[c["j"]] = j
        formulas = {"turn": f"=syn_alpha{j}-syn_alpha1",
                    "beta": f"=syn_beta{j}" if j > 1 else "=0",
                    "gamma": f"=syn_gamma{j}" if j > 1 else "=0",
                    "dx": f"=syn_x{j}-syn_x1", "dy": f"=syn_y{j}-syn_y1"}
        for part, angle in (("b", "beta"), ("c", "turn"), ("g", "gamma")):
            formulas[f"{part}_re"] = f"=-2*SIN(RADIANS({c[angle]})/2)^2"
            formulas[f"{part}_im"] = f"=SIN(RADIANS({c[angle]}))"
        for key, text in formulas.items():
            set_formula(ws[c[key]], text)
            ws[c[key]].number_format = number_format(
                DEG if key in ("turn", "beta", "gamma") else LENGTH if key in LENGTH_KEYS
                else RATIO)
        for key, cell in c.items():
            out[key].append(cell)
    return out


def _times(p: tuple[str, str], q: tuple[str, str]) -> tuple[str, str]:
    """The real and imaginary parts of the product of two complex numbers (cells)."""
    return (f"{p[0]}*{q[0]}-{p[1]}*{q[1]}", f"{p[0]}*{q[1]}+{p[1]}*{q[0]}")


def _dyad(b: _Block, dyad: str, poses: dict[str, list[str]], turn: tuple[str, str]) -> None:
    """One dyad's system by Cramer's rule: D, the numerators, the solution (W, Z for the
    crank, U, S for the rocker), and the condition of its matrix [B_j, C_j]."""
    first, second = ("W", "Z") if dyad == "crank" else ("U", "S")
    rho = "β" if dyad == "crank" else "γ"
    b.title(f"The {dyad}'s dyad: {first}·(e^{{i{rho}_j}} − 1) + {second}·(e^{{iα_j}} − 1) = "
            f"δ_j, j = 2, 3, by Cramer's rule")
    B = [(poses[turn[0]][j], poses[turn[1]][j]) for j in (1, 2)]     # noqa: N806  B_2, B_3
    C = [(poses["c_re"][j], poses["c_im"][j]) for j in (1, 2)]       # noqa: N806
    delta = [(poses["dx"][j], poses["dy"][j]) for j in (1, 2)]
    k = dyad[0]                                    # c or r: the keys' prefix
    det = [f"({p})-({q})" for p, q in zip(_times(B[0], C[1]), _times(B[1], C[0]))]
    d = (b.add(f"{k}_D_re", f"Re D = Re(B_2·C_3 − B_3·C_2)", "Re D", f"={det[0]}", RATIO),
         b.add(f"{k}_D_im", "Im D", "Im D", f"={det[1]}", RATIO))
    d2 = b.add(f"{k}_D2", "|D|²", "|D|²", f"={d[0]}^2+{d[1]}^2", RATIO)
    numerators = {first: [f"({p})-({q})" for p, q in zip(_times(delta[0], C[1]),
                                                          _times(delta[1], C[0]))],
                  second: [f"({p})-({q})" for p, q in zip(_times(B[0], delta[1]),
                                                           _times(B[1], delta[0]))]}
    what = {first: "δ_2·C_3 − δ_3·C_2", second: "B_2·δ_3 − B_3·δ_2"}
    n = {}
    for v, (re, im) in numerators.items():
        n[v] = (b.add(f"{k}_N{v}_re", f"Re N_{v} = Re({what[v]})", f"Re N_{v}", f"={re}",
                      LENGTH),
                b.add(f"{k}_N{v}_im", f"Im N_{v}", f"Im N_{v}", f"={im}", LENGTH))
    entries = "+".join(f"{re}^2+{im}^2" for re, im in (*B, *C))
    f = b.add(f"{k}_F", "F = Σ|entries|² of [B_j, C_j]", "F", f"={entries}", RATIO)
    t1 = b.add(f"{k}_t1", "t₁ = (F + √(F² − 4|D|²))/2", "t₁",
               f"=({f}+{in_domain_or_na('SQRT', f'MAX(0,{f}^2-4*{d2})')})/2", RATIO)
    t2 = b.add(f"{k}_t2", "t₂ = |D|²/t₁", "t₂", f"=IF({t1}>0,{d2}/{t1},0)", RATIO)
    b.add(f"{k}_condition", "condition number cond₂ = √(t₁/t₂)", "cond₂",
          f"=IF({t2}>0,{in_domain_or_na('SQRT', f'{t1}/{t2}')},NA())", RATIO)
    # t₂ = 0 (the matrix of rank 1 or 0) is cond₂ = ∞
    singular = f"OR({t2}<=0,{t1}>{SINGULAR_COND ** 2:G}*{t2})"
    b.add(f"{k}_system", f"the {dyad}'s system", "",
          f'=IF({singular},"{WORDS["singular"]}","{WORDS["solvable"]}")', "")
    for v in (first, second):
        re, im = n[v]
        b.add(f"{v}_x", f"{v}_x = Re(N_{v}/D) (#N/A where near-singular)", f"{v}_x",
              f"=IF({singular},NA(),({re}*{d[0]}+{im}*{d[1]})/{d2})", LENGTH,
              name=f"syn_{v}x")
        b.add(f"{v}_y", f"{v}_y = Im(N_{v}/D)", f"{v}_y",
              f"=IF({singular},NA(),({im}*{d[0]}-{re}*{d[1]})/{d2})", LENGTH,
              name=f"syn_{v}y")


def _dyad_about_pivot(b: _Block, dyad: str, poses: dict[str, list[str]]) -> None:
    """One dyad about its given fixed pivot G (Norton §5.9): M_j's distance from G the same at
    every pose, linear in m = M − P_1 (e_1 = P_1 − G, e^{−iα_j} = 1 + (cos α_j − 1) −
    i·sin α_j): 2·[e^{−iα_j}·δ_j + (e^{−iα_j} − 1)·e_1]·m = −δ_j·(2e_1 + δ_j), j = 2, 3, by
    Cramer's rule; its condition as the reference states it; then W = e_1 + m, Z = −m (U, S)
    and the dyad's rotations β_j (γ_j), now results."""
    first, second = ("W", "Z") if dyad == "crank" else ("U", "S")
    k, key, g = dyad[0], ("beta" if dyad == "crank" else "gamma"), PIVOTS[dyad]
    b.title(f"The {dyad}'s dyad about its given pivot {g}: |M_j − {g}| = |M_1 − {g}|, "
            "linear in m = M − P_1, by Cramer's rule")
    ex = b.add(f"{k}_e1_x", f"e_1 = P_1 − {g}, x", "e_1x", f"=syn_x1-syn_{dyad}_x", LENGTH)
    ey = b.add(f"{k}_e1_y", "e_1, y", "e_1y", f"=syn_y1-syn_{dyad}_y", LENGTH)
    rows, rhs, row_terms, rhs_terms = [], [], [], []
    for j in (2, 3):
        cr, ci = poses["c_re"][j - 1], poses["c_im"][j - 1]
        dx, dy = poses["dx"][j - 1], poses["dy"][j - 1]
        rows.append((
            b.add(f"{k}_row{j}_x", f"row {j}: 2·Re(e^{{−iα_{j}}}·δ_{j} + (e^{{−iα_{j}}} − 1)·e_1)",
                  f"R_{j}x", f"=2*((1+{cr})*{dx}+{ci}*{dy}+{cr}*{ex}+{ci}*{ey})", LENGTH),
            b.add(f"{k}_row{j}_y", f"row {j}: 2·Im(…)", f"R_{j}y",
                  f"=2*((1+{cr})*{dy}-{ci}*{dx}+{cr}*{ey}-{ci}*{ex})", LENGTH)))
        rhs.append(b.add(f"{k}_rhs{j}", f"right-hand side {j}: −δ_{j}·(2e_1 + δ_{j})", f"r_{j}",
                         f"=-({dx}*(2*{ex}+{dx})+{dy}*(2*{ey}+{dy}))", "length²"))
        delta = f"SQRT({dx}^2+{dy}^2)"
        row_terms.append(f"2*({delta}+SQRT({cr}^2+{ci}^2)*SQRT({ex}^2+{ey}^2))")
        rhs_terms.append(f"{delta}*(2*SQRT({ex}^2+{ey}^2)+{delta})")
    (r2x, r2y), (r3x, r3y) = rows
    det = b.add(f"{k}_det", "determinant R_2x·R_3y − R_2y·R_3x", "D", f"={r2x}*{r3y}-{r2y}*{r3x}",
                "length²")
    mx = b.add(f"{k}_mx", "m_x by Cramer's rule", "m_x",
               f"=IF({det}=0,NA(),({rhs[0]}*{r3y}-{r2y}*{rhs[1]})/{det})", LENGTH)
    my = b.add(f"{k}_my", "m_y by Cramer's rule", "m_y",
               f"=IF({det}=0,NA(),({r2x}*{rhs[1]}-{rhs[0]}*{r3x})/{det})", LENGTH)
    f = b.add(f"{k}_F", "F = Σ entries² of the rows", "F",
              f"={r2x}^2+{r2y}^2+{r3x}^2+{r3y}^2", "length²")
    t1 = b.add(f"{k}_t1", "t₁ = (F + √(F² − 4D²))/2", "t₁",
               f"=({f}+{in_domain_or_na('SQRT', f'MAX(0,{f}^2-4*{det}^2)')})/2", "length²")
    t2 = b.add(f"{k}_t2", "t₂ = D²/t₁ (the smallest singular value²)", "t₂",
               f"=IF({t1}>0,{det}^2/{t1},0)", "length²")
    b.add(f"{k}_condition", "condition: (largest row term + largest right-hand term/|m|)/√t₂",
          "cond", f"=IF({t2}>0,(MAX({','.join(row_terms)})+MAX({','.join(rhs_terms)})"
                  f"/MAX(SQRT({mx}^2+{my}^2),1E-300))/{in_domain_or_na('SQRT', t2)},NA())",
          RATIO)
    singular = f"IF({t2}<=0,TRUE,{b.cells[f'{k}_condition']}>{SINGULAR_COND:G})"
    b.add(f"{k}_system", f"the {dyad}'s system", "",
          f'=IF({singular},"{WORDS["singular"]}","{WORDS["solvable"]}")', "")
    for v, (x, y) in ((first, (f"{ex}+{mx}", f"{ey}+{my}")), (second, (f"-{mx}", f"-{my}"))):
        b.add(f"{v}_x", f"{v}_x (#N/A where near-singular)", f"{v}_x",
              f"=IF({singular},NA(),{x})", LENGTH, name=f"syn_{v}x")
        b.add(f"{v}_y", f"{v}_y", f"{v}_y", f"=IF({singular},NA(),{y})", LENGTH,
              name=f"syn_{v}y")
    symbol = "β" if dyad == "crank" else "γ"
    for j in (2, 3):
        cr, ci = poses["c_re"][j - 1], poses["c_im"][j - 1]
        vx = (f"syn_{first}x+{poses['dx'][j - 1]}-({cr}*syn_{second}x-{ci}*syn_{second}y)")
        vy = (f"syn_{first}y+{poses['dy'][j - 1]}-({cr}*syn_{second}y+{ci}*syn_{second}x)")
        b.add(f"{key}{j}", f"the {dyad}'s rotation from pose 1 to {j} (a result)",
              f"{symbol}_{j}", f"=180-MOD(180-(DEGREES(ATAN2({vx},{vy}))"
                               f"-DEGREES(ATAN2(syn_{first}x,syn_{first}y))),360)", DEG,
              name=f"syn_{key}{j}")


def _four_bar(b: _Block) -> None:
    """The pivots, the lengths, whether a four-bar exists (no link too short), the coupler
    point and the coupler's offset."""
    b.title("The designed four-bar: pivots, lengths, coupler point")
    for point, formula in (("A", ("syn_x1-syn_Zx", "syn_y1-syn_Zy")),
                           ("A0", ("syn_xA-syn_Wx", "syn_yA-syn_Wy")),
                           ("B", ("syn_x1-syn_Sx", "syn_y1-syn_Sy")),
                           ("B0", ("syn_xB-syn_Ux", "syn_yB-syn_Uy"))):
        where = {"A": "the crank's pin at pose 1, P_1 − Z", "A0": "the crank's pivot, A − W",
                 "B": "the rocker's joint at pose 1, P_1 − S",
                 "B0": "the rocker's pivot, B − U"}[point]
        for axis, text in zip("xy", formula):
            b.add(f"{axis}{point}", f"{axis} of {point}: {where}" if axis == "x" else
                  f"y of {point}", f"{axis}_{point}", f"={text}", LENGTH,
                  name=f"syn_{axis}{point}")
    for key, label, symbol, text in (
            ("a", "crank a = |W|", "a", "SQRT(syn_Wx^2+syn_Wy^2)"),
            ("b", "coupler b = |Z − S|", "b", "SQRT((syn_Zx-syn_Sx)^2+(syn_Zy-syn_Sy)^2)"),
            ("c", "rocker c = |U|", "c", "SQRT(syn_Ux^2+syn_Uy^2)"),
            ("d", "ground d = |W + Z − U − S|", "d",
             "SQRT((syn_Wx+syn_Zx-syn_Ux-syn_Sx)^2+(syn_Wy+syn_Zy-syn_Uy-syn_Sy)^2)")):
        b.add(key, label, symbol, f"={text}", LENGTH, name=f"syn_{key}")
    deltas = ",".join(f"SQRT((syn_x{j}-syn_x1)^2+(syn_y{j}-syn_y1)^2)" for j in (2, 3))
    size = b.add("size", "the task's size: the largest of a, b, c, d, |δ_2|, |δ_3|", "L",
                 f"=MAX(syn_a,syn_b,syn_c,syn_d,{deltas})", LENGTH, name="syn_size")
    solvable = f'AND({b.cells["c_system"]}="{WORDS["solvable"]}",' \
               f'{b.cells["r_system"]}="{WORDS["solvable"]}")'
    b.add("exists", "a four-bar: both systems solvable, every link > 10⁻⁹·L", "",
          f"=IF({solvable},MIN(syn_a,syn_b,syn_c,syn_d)>{DEGENERATE:G}*{size},FALSE)", "",
          name="syn_exists")
    b.add("short", "the links against the task's size", "",
          f'=IF({solvable},IF(syn_exists,"{WORDS["long enough"]}","{WORDS["too short"]}"),'
          f"NA())", "")
    along = "SQRT((syn_Zx-syn_Sx)^2+(syn_Zy-syn_Sy)^2)"
    b.add("u", "coupler point u = Z·(Z − S)/b, along A→B", "u",
          f"=IF(syn_exists,(syn_Zx*(syn_Zx-syn_Sx)+syn_Zy*(syn_Zy-syn_Sy))/{along},NA())",
          LENGTH, name="syn_u")
    b.add("v", "coupler point v = ((Z − S) × Z)/b, left of A→B", "v",
          f"=IF(syn_exists,((syn_Zx-syn_Sx)*syn_Zy-(syn_Zy-syn_Sy)*syn_Zx)/{along},NA())",
          LENGTH, name="syn_v")
    b.add("offset", "coupler offset ε = α_1 − ∠(Z − S), in (−180°, 180°]", "ε",
          "=IF(syn_exists,180-MOD(180-(syn_alpha1-DEGREES(ATAN2(syn_Zx-syn_Sx,"
          "syn_Zy-syn_Sy))),360),NA())", DEG, name="syn_offset")


def _at_pose_table(ws, t: Template, model: Model, names: dict[str, str], head: int
                   ) -> dict[str, list[str]]:
    """The designed linkage at each pose: its crank and rocker angles, the branch, the
    transmission angle, and the coupler point and angle the position steps give at θ2_j
    against the pose: the live check that the linkage passes through its poses."""
    task: DyadTask = t.synthesis
    letter = _head(ws, head, "The designed linkage at each pose: placed by the position steps "
                             "at θ2_j, against the pose", AT_POSE_COLUMNS)
    out: dict[str, list[str]] = {key: [] for key, _ in AT_POSE_COLUMNS}
    for j in range(1, 4):
        r = head + j
        c = {key: f"{letter[key]}{r}" for key in letter}
        ws[c["j"]] = j
        steps = Resolver(model, names, {t.mechanism.input_column: c["theta2"]})
        rotation = {1: ("0", "0")}.get(j, (f"syn_beta{j}", f"syn_gamma{j}"))
        a = f"RADIANS({c['theta2']})"
        g = f"RADIANS({c['theta4']})"
        reach = (f"(syn_xA0-syn_xB0+syn_a*COS({a}))", f"(syn_yA0-syn_yB0+syn_a*SIN({a}))")
        cross = f"syn_c*COS({g})*{reach[1]}-syn_c*SIN({g})*{reach[0]}"
        s2 = f"{reach[0]}^2+{reach[1]}^2"      # a sum of squares: its root needs no test
        formulas = {
            "theta2": f"=IF(syn_exists,DEGREES(ATAN2(syn_Wx,syn_Wy))+{rotation[0]},NA())",
            "theta4": f"=IF(syn_exists,DEGREES(ATAN2(syn_Ux,syn_Uy))+{rotation[1]},NA())",
            "cross": f"={cross}",
            "branch": f"=IF(ABS({c['cross']})<={DEAD_CENTRE:G}*syn_c*SQRT({s2}),0,"
                      f"SIGN({c['cross']}))",
            "mu": f"=DEGREES({acos_or_na(f'(syn_b^2+syn_c^2-({s2}))/(2*syn_b*syn_c)')})",
            "x": steps.formula(task.key("x")), "y": steps.formula(task.key("y")),
            "angle": f"=180-MOD(180-DEGREES({steps.formula(task.key('theta3'))[1:]})"
                     f"-syn_offset,360)",
            "miss_x": f"={c['x']}-syn_x{j}", "miss_y": f"={c['y']}-syn_y{j}",
            "miss_angle": f"=MOD({c['angle']}-syn_alpha{j}+180,360)-180"}
        for key, text in formulas.items():
            set_formula(ws[c[key]], text)
            if key != "branch":
                ws[c[key]].number_format = number_format(
                    LENGTH if key in LENGTH_KEYS else DEG, t.length_unit)
        for key, cell in c.items():
            out[key].append(cell)
    return out


def _checks(b: _Block, at: dict[str, list[str]]) -> None:
    """The checks in words: the branch at the poses (and their common branch), Grashof's
    class, the transmission angle's range over the poses."""
    b.title("Checks")
    branches = f"{at['branch'][0]}:{at['branch'][-1]}"
    b.add("defect", "the branch at the poses", "",
          f'=IF(AND(MAX({branches})=1,MIN({branches})=-1),"{WORDS["defect"]}",'
          f'"{WORDS["no defect"]}")', "")
    b.add("branch", "their common branch (1 open, −1 crossed)", "",
          f"=IF(MAX({branches})=1,IF(MIN({branches})=-1,NA(),1),"
          f"IF(MIN({branches})=-1,-1,NA()))", "")
    b.add("grashof", "Grashof class of the designed linkage", "",
          "=IF(syn_exists," + grashof_formula("syn_d", "syn_a", "syn_b", "syn_c") + ",NA())",
          "")
    mu = f"{at['mu'][0]}:{at['mu'][-1]}"
    b.add("mu_min", "smallest transmission angle at the poses", "μ", f"=MIN({mu})", DEG)
    b.add("mu_max", "largest transmission angle at the poses", "μ", f"=MAX({mu})", DEG)


def _designed(b: _Block, task: DyadTask) -> None:
    """The designed parameters' named cells: #N/A unless a four-bar exists on one branch."""
    b.title("The designed parameters: every other sheet reads these named cells")
    usable = b.add("usable", "a linkage to analyse (a four-bar, one branch at all poses)", "",
                   f"=IF(syn_exists,ABS({b.cells['branch']})=1,FALSE)", "")
    values = {"crank": "syn_a", "coupler": "syn_b", "rocker": "syn_c", "ground": "syn_d",
              "u": "syn_u", "v": "syn_v", "offset": "syn_offset", "xA0": "syn_xA0",
              "yA0": "syn_yA0", "xB0": "syn_xB0", "yB0": "syn_yB0",
              "branch": b.cells["branch"]}
    for role, symbol in task.designs:
        p = b.t.parameter(symbol)
        b.add(f"designed_{role}", f"{p.label} (designed)", symbol,
              f"=IF({usable},{values[role]},NA())",
              "" if role == "branch" else DEG if role == "offset" else LENGTH, name=p.name)


def _misses(ws, b: _Block, at: dict[str, list[str]], head: int) -> None:
    """The largest miss of the poses, beside the table: the distance of the coupler point
    from P_j and the coupler angle's miss, by the position steps."""
    col = TABLE_COLUMN + len(AT_POSE_COLUMNS) + 1
    label, value = get_column_letter(col), get_column_letter(col + 1)
    angle = f"{at['miss_angle'][0]}:{at['miss_angle'][-1]}"
    distances = ",".join(f"SQRT({p}^2+{q}^2)" for p, q in zip(at["miss_x"], at["miss_y"]))
    for i, (key, text, formula, unit) in enumerate((
            ("largest_miss", "largest |P − P_j| by the steps", f"=MAX({distances})", LENGTH),
            ("largest_angle_miss", "largest |angle − α_j| [deg]",
             f"=MAX(MAX({angle}),-MIN({angle}))", DEG))):
        r = head + 1 + i
        put_text(ws, f"{label}{r}", text, BOLD)
        ws.column_dimensions[label].width = max(ws.column_dimensions[label].width or 12,
                                                column_width(text, bold=True))
        set_formula(ws[f"{value}{r}"], formula)
        ws[f"{value}{r}"].number_format = number_format(unit, b.t.length_unit)
        b.cells[key] = f"{value}{r}"


def _drawing(ws, t: Template, model: Model, names: dict[str, str], head: int,
             angles: list[str]) -> dict:
    """The designed linkage at each pose's θ2_j by the position steps, and the live frame of
    its drawing (synthesis_drawing.py), under the table of the poses it checks."""
    first = get_column_letter(TABLE_COLUMN)
    put_text(ws, f"{first}{head - 1}", "The designed linkage at each pose (the position steps "
                                       "at θ2_j), drawn to scale", BOLD)
    positions = joints_at(ws, t, model, names, head, TABLE_COLUMN, angles)
    drawing = positions_drawing(ws, t, positions, head, TABLE_COLUMN + 6)
    drawing["title"] = "The designed linkage at each pose"
    return drawing


def _fit(ws, heads: tuple[int, ...]) -> None:
    """Column A as wide as its longest label, and the tables' headers whole."""
    labels = [c.value for (c,) in ws.iter_rows(min_row=8, min_col=1, max_col=1)
              if isinstance(c.value, str) and not c.font.b]
    ws.column_dimensions["A"].width = max([ws.column_dimensions["A"].width or 12] +
                                          [column_width(text) for text in labels])
    for row in heads:
        fit_heads(ws, row, [get_column_letter(c) for c in range(TABLE_COLUMN, ws.max_column + 1)
                            if isinstance(ws.cell(row, c).value, str)])
