"""Judging a book's Synthesis sheet (function generation, docs/synthesis.md): the task's inputs
read from the book's own cells, the linkage designed by the independent reference
(reference/synthesis.py), every cell of the sheet compared with it, and the designed values
handed to the kinematic and force references, which judge the analysis sheets as for any book.

Nothing here reads the writer or the language: f is evaluated by the reference's own reader of
expressions, and the words the sheet states are base.sheets.SYNTHESIS_WORDS. Motion and path
generation are synthesis_dyads.py's: the public functions here dispatch on the task's kind.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..base.record import BuildRecord
from ..base.sheets import DASH, SYNTHESIS_WORDS as WORDS
from .checks import ABS_TOL, Check, Mismatch, compare_exact
from .cells import number_at
from .reference import evaluate
from .reference import synthesis as ref
from . import synthesis_dyads as dyads
from .reference.fourbar import grashof_class

EPS = float(np.finfo(float).eps)
# The bound of the cells the solve gives (the system's determinants, K1-K3, the lengths, the
# residuals, the transmission angles, the condition), relative to each value: two correct
# solutions of a linear system of condition κ differ by up to about κ·ε relative (ε = 2.2e-16)
# and the normal equations square κ, which beyond three points the book solves and the
# reference does not (numpy's lstsq). The bound is SOLVE_MARGIN·ε·κ (κ² beyond three points),
# never below the 1e-9 of any other cell: at the bundled task's κ = 15 that is the 1e-9
# itself. The margin covers the constant of those estimates (Cramer's rule on the 3×3, the
# sums of n products): random tasks (tests/test_synthesis_book.py) reach about 130·ε·κ².
# The lengths get it normwise (length_errors), the transmission angles through ACOS.
SOLVE_MARGIN = 1000.0
TASK_KEYS = ("x0", "x1", "theta2_start", "theta2_span", "theta4_start", "theta4_span")
POINT_UNITS = {"x": "-", "y": "-", "theta2_deg": "deg", "theta4_deg": "deg", "theta2": "rad",
               "theta4": "rad", "m1": "-", "m2": "-", "m3": "-", "r": "-", "residual": "-",
               "cross": "length²", "branch": "-", "generated": "rad", "error": "deg"}


@dataclass
class Design:
    """The task as the book holds it and the reference's design of it."""
    x: np.ndarray
    y: np.ndarray
    theta2: np.ndarray          # radians
    theta4: np.ndarray
    task: dict                  # the task's numbers: x0 … theta4_span, d, f(x0), f(x1)
    result: dict                # reference.synthesis.function_generation's
    designed: dict              # {symbol: value} of the designed parameters (NaN: none)

    @property
    def usable(self) -> bool:
        return all(math.isfinite(v) for v in self.designed.values())


def f_of(record: BuildRecord):
    """f as a function over numpy arrays, by the reference's reader of expressions."""
    text = record.synthesis.task["f"]
    return lambda x: np.asarray(evaluate(text, {"x": np.asarray(x, dtype=float)}) + 0.0 * x,
                                dtype=float)


def task_inputs(wb, record: BuildRecord) -> dict[str, float]:
    """The task's inputs as the book's Synthesis cells hold them, by the record's keys (x0 …
    theta4_span, and x_1 … x_n where the x values are given)."""
    syn = record.synthesis
    ws = wb[syn.sheet]
    return {key: number_at(ws, cell, f"the task's {key}") for key, cell in syn.inputs.items()}


def design_of(wb, record: BuildRecord, ground: float) -> Design:
    """The reference's design of the task the book's Synthesis cells hold."""
    return design_for(record, task_inputs(wb, record), ground)


def design_for(record: BuildRecord, inputs: dict[str, float], ground: float) -> Design:
    """The reference's design of the record's task with these inputs (task_inputs' keys) and
    this ground length."""
    spec = record.synthesis.task
    task = {key: inputs[key] for key in TASK_KEYS}
    f = f_of(record)
    if spec["spacing"] == "given":
        given = [inputs[f"x_{j}"] for j in range(1, spec["points"] + 1)]
        x, y = ref.precision_points(f, task["x0"], task["x1"], spec["points"], given=given)
    else:
        x, y = ref.precision_points(f, task["x0"], task["x1"], spec["points"], spec["spacing"])
    theta2, theta4 = ref.precision_angles(
        f, x, task["x0"], task["x1"], *np.radians([task["theta2_start"], task["theta2_span"],
                                                   task["theta4_start"], task["theta4_span"]]))
    result = ref.function_generation(theta2, theta4, ground, input_range=(
        math.radians(task["theta2_start"]), math.radians(task["theta2_span"])))
    task.update(d=ground, f_x0=float(f(np.array([task["x0"]]))[0]),
                f_x1=float(f(np.array([task["x1"]]))[0]))
    return Design(x, y, theta2, theta4, task, result, _designed(result, spec["designs"]))


def _designed(result: dict, designs: dict) -> dict[str, float]:
    """What the book's designed cells must hold: the lengths and the branch of a linkage with
    a > 0, c > 0, b > 0 on one branch at every point; else NaN (#N/A) for every one."""
    a, b, c = result["a"], result["b"], result["c"]
    used = {float(s) for s in result["branch"] if math.isfinite(s) and s != 0}
    usable = all(math.isfinite(v) for v in (a, b, c)) and a > 0 and c > 0 and b > 0 \
        and len(used) == 1
    values = {"crank": a, "coupler": b, "rocker": c, "branch": used.pop() if usable else 0.0}
    return {symbol: values[role] if usable else math.nan for role, symbol in designs.items()}


def designed_values(wb, record: BuildRecord, values: dict[str, float]) -> dict[str, float]:
    """`values` (the inputs read from the book) with the designed parameters' values."""
    if record.synthesis is None:
        return values
    return with_design(record, values, task_inputs(wb, record))


def _dyads(record: BuildRecord) -> bool:
    """Is the record's task motion or path generation (synthesis_dyads.py's)?"""
    return record.synthesis.task["kind"] != "function"


def with_design(record: BuildRecord, values: dict[str, float], inputs: dict[str, float]
                ) -> dict[str, float]:
    """`values` with the designed parameters' values: the reference's design of the task with
    these `inputs` (task_inputs' keys) at the ground length `values` hold."""
    if _dyads(record):
        return dyads.with_design(record, values, inputs)
    ground = values[record.synthesis.task["ground"]]
    designed = design_for(record, inputs, ground).designed
    branch = record.synthesis.task["designs"]["branch"]
    if math.isnan(designed[branch]):
        # no linkage: its lengths NaN put every analysis cell at #N/A whichever branch the
        # references are told, and they want ±1
        designed[branch] = 1.0
    return {**values, **designed}


def why_no_design(record: BuildRecord, inputs: dict[str, float], values: dict[str, float]
                  ) -> str | None:
    """Why the task with these `inputs` (and the ground length `values` hold) designs no
    linkage to analyse, in words; None where it designs one."""
    if _dyads(record):
        return dyads.no_design_because(dyads.design_for(record, inputs).result)
    ground = values[record.synthesis.task["ground"]]
    return no_design_because(design_for(record, inputs, ground).result)


def task_table(record: BuildRecord, inputs: dict[str, float]) -> dict:
    """The [synthesis] table of the record's task with these inputs, as a template states it
    (the language checks a moved task with it)."""
    spec = record.synthesis.task
    if _dyads(record):
        return dyads.task_table(spec, inputs)
    given = [inputs[f"x_{j}"] for j in range(1, spec["points"] + 1)] \
        if spec["spacing"] == "given" else spec["spacing"]
    return {"kind": "function", "f": spec["f"], "x": [inputs["x0"], inputs["x1"]],
            "points": spec["points"], "theta2": [inputs["theta2_start"], inputs["theta2_span"]],
            "theta4": [inputs["theta4_start"], inputs["theta4_span"]], "spacing": given,
            "ground": spec["ground"], "designs": spec["designs"]}


def no_design_because(result: dict) -> str | None:
    """Why the reference's design `result` is no linkage to analyse, in words; None where it
    is one (_designed's test)."""
    a, b, c = result["a"], result["b"], result["c"]
    if result["singular"]:
        return "its system is near-singular"
    if result["branch_defect"]:
        return "a branch defect"
    if not all(math.isfinite(v) for v in (a, b, c)) or b <= 0:
        return "no real coupler length"
    if a <= 0 or c <= 0:
        return "a negative crank or rocker"
    if not any(math.isfinite(s) and s != 0 for s in result["branch"]):
        return "a dead centre at every precision point"
    return None


def solve_bound(result: dict, points: int) -> float:
    """The relative bound of the solve's cells (SOLVE_MARGIN)."""
    kappa = result["condition"]
    return max(ABS_TOL, SOLVE_MARGIN * EPS * kappa ** (1 if points == 3 else 2))


def length_errors(result: dict, tol: float) -> dict[str, float]:
    """The relative error each designed length may carry when K1-K3 are solved to `tol`
    (solve_bound). A linear solve's error is bounded normwise: each K_i may be off by
    tol·max(1, ‖K‖∞), which is far more than tol·|K_i| for a small one, and a = d/K1, c = d/K2
    carry that over |K1|, |K2|. b² = a² + c² + d² − 2ac·K3 adds its terms' errors, which its
    cancellation magnifies (over b², not over its terms' sizes)."""
    k = np.abs(np.asarray(result["coefficients"], dtype=float))
    a, b, c = result["a"], result["b"], result["c"]
    if not np.isfinite(k).all() or not all(math.isfinite(v) for v in (a, b, c)) or b == 0:
        return {"K": tol, "a": tol, "c": tol, "K3": tol, "b": tol}
    each = tol * max(1.0, float(k.max()))
    ra, rc, r3 = (each / max(v, 1e-300) for v in k)
    rb = (a * a * ra + c * c * rc + abs(a * c * result["K3"]) * (ra + rc + r3)) / (b * b)
    return {"K": each, "a": max(tol, ra), "c": max(tol, rc), "K3": r3, "b": max(tol, rb)}


def as_designed(wb, record: BuildRecord, values: dict, params: dict) -> dict[str, float]:
    """The parameters the analysis sheets are judged with: the book's own designed values
    wherever they agree with the reference's design within the solve's bound (the designed
    cells are judged against it, check_synthesis), so that the kinematic and force references
    analyse the linkage the book designed; the reference's where they do not (a wrong design
    is reported there, and its analysis judged against the right one)."""
    if _dyads(record):
        return dyads.as_designed(record, task_inputs(wb, record), values, params)
    syn = record.synthesis
    design = design_of(wb, record, params[syn.task["ground"]])
    errors = length_errors(design.result, solve_bound(design.result, syn.task["points"]))
    bounds = {"crank": errors["a"], "coupler": errors["b"], "rocker": errors["c"], "branch": 0}
    out = dict(params)
    for role, symbol in syn.task["designs"].items():
        want, got = params[symbol], values.get((syn.sheet, syn.cells[f"designed_{role}"]))
        if isinstance(got, (int, float)) and not isinstance(got, bool) and \
                math.isfinite(want) and abs(got - want) <= bounds[role] * max(abs(want), 1e-300):
            out[symbol] = float(got)
    return out


# ---------------------------------------------------------------- the checks
def check_synthesis(j) -> np.ndarray:
    """Every cell of the Synthesis sheet but its drawing, and the Mechanism sheet's links to
    the designed cells, against the reference's design (j: context.Judging). Returns the
    reference's crank angle θ2_j at each precision point or pose, in degrees, at which
    synthesis_drawing.py (run by judge.py) places the designed linkage."""
    if _dyads(j.record):
        return dyads.check_synthesis(j, task_inputs(j.wb, j.record))
    syn = j.record.synthesis
    ground = j.params[syn.task["ground"]]
    design = design_of(j.wb, j.record, ground)
    res = design.result
    n = syn.task["points"]
    solved = replace(j.rules, tol=solve_bound(res, n), relative=True)
    sheet, cells = syn.sheet, syn.cells
    for key in ("d", "f_x0", "f_x1"):
        j.run("synthesis", key, sheet, [cells[key]], np.array([design.task[key]]),
              "length" if key == "d" else "-")
    _check_points(j, design, solved)
    _check_solution(j, design, solved, n)
    _check_words(j, design)
    _check_designed(j, design, solved)
    _check_error_table(j, design)
    return np.degrees(design.theta2)


def _run(j, name: str, sheet: str, cells: list[str], expected, unit: str, rules=None,
         slope=None, dead=None) -> None:
    from .checks import unit_scale
    c = Check("synthesis", name, j.size, 1.0, unit_scale(unit, j.size))
    j.compare(c, sheet, cells, np.asarray(expected, dtype=float), unit, slope, dead,
              rules=rules)
    j.checks.append(c)


def _output_slopes(j, theta2_deg: np.ndarray) -> dict:
    """slope(i) for the columns that read the designed linkage's output angle by the position
    steps (θ4 in radians, the structural error in degrees): near a dead centre (the transmission
    angle near 0° or 180°, as at a precision point close to a branch defect) any evaluation of
    θ4 loses digits like 1/sin μ, and so does its slope ∂θ4/∂θ2: the allowance near a limit
    position the Sweep's θ4 gets (checks.compare)."""
    output = j.record.synthesis.task["output"]
    return {"generated": j.slope(theta2_deg, output, "rad"),
            "error": j.slope(theta2_deg, f"{output}_deg", "deg")}


def _check_points(j, design: Design, solved) -> None:
    syn, res = j.record.synthesis, design.result
    m, r = ref.freudenstein_matrix(design.theta2, design.theta4)
    d = design.task["d"]
    a, c = res["a"], res["c"]
    generated = _generated(j, design, np.degrees(design.theta2))
    expected = {
        "x": design.x, "y": design.y, "theta2_deg": np.degrees(design.theta2),
        "theta4_deg": np.degrees(design.theta4), "theta2": design.theta2,
        "theta4": design.theta4, "m1": m[:, 0], "m2": m[:, 1], "m3": m[:, 2], "r": r,
        "residual": res["residual"],
        "cross": c * np.cos(design.theta4) * a * np.sin(design.theta2)
        - c * np.sin(design.theta4) * (a * np.cos(design.theta2) - d),
        "branch": res["branch"], "generated": generated,
        "error": _wrapped(np.degrees(generated) - np.degrees(design.theta4)),
    }
    products = {"m11": (0, 0), "m12": (0, 1), "m13": (0, 2), "m22": (1, 1), "m23": (1, 2),
                "m33": (2, 2)}
    for key, (p, q) in products.items():
        expected[key] = m[:, p] * m[:, q]
    for k in range(3):
        expected[f"v{k + 1}"] = m[:, k] * r
    # the residual's terms are K·cos: its error is the coefficients' times their size
    residual = replace(solved, tol=solved.tol * (1.0 + float(np.nansum(np.abs(
        res["coefficients"])))), relative=False)
    # cross's terms are products of a·c or c·d (each of relative error up to 2·tol): its error
    # is that times the terms' sizes, which may cancel (the sum of their sizes over |cross|)
    terms = np.abs(c) * (np.abs(a * np.cos(design.theta4) * np.sin(design.theta2))
                         + np.abs(np.sin(design.theta4)) * (np.abs(a * np.cos(design.theta2))
                                                            + d))
    with np.errstate(invalid="ignore", divide="ignore"):
        cancel = np.nanmax(np.append(terms / np.abs(expected["cross"]), 1.0))
    errors = length_errors(res, solved.tol)
    cross = replace(solved, tol=(errors["a"] + errors["c"]) * min(cancel, 1e300))
    slopes = _output_slopes(j, np.degrees(design.theta2))
    for key, cells in syn.points.items():
        unit = POINT_UNITS.get(key, "-")
        rules = residual if key == "residual" else cross if key == "cross" else None
        _run(j, key, syn.sheet, list(cells), expected[key], unit, rules, slopes.get(key))


def _check_solution(j, design: Design, solved, n: int) -> None:
    syn, res = j.record.synthesis, design.result
    m, r = ref.freudenstein_matrix(design.theta2, design.theta4)
    normal, rhs = m.T @ m, m.T @ r
    system = np.column_stack([m, r]) if n == 3 else np.column_stack([normal, rhs])
    cells = syn.cells
    expected = {f"S{i + 1}{k + 1}": system[i, k] for i in range(3) for k in range(4)}
    lam = np.linalg.eigvalsh(normal)
    q = np.trace(normal) / 3
    p = math.sqrt(float(np.sum((lam - q) ** 2)) / 6)
    half = float(np.prod(lam - q)) / p ** 3 / 2
    eig = {"eig_mean": q, "eig_p": p, "eig_r": half,
           "eig_phi": math.acos(max(-1.0, min(1.0, half))) / 3,
           "eig_max": lam[-1], "eig_min": lam[0]}
    singular = res["singular"]
    square = system[:, :3]
    expected["D"] = np.linalg.det(square)
    for k in range(3):
        replaced = square.copy()
        replaced[:, k] = system[:, 3]
        expected[f"D{k + 1}"] = np.linalg.det(replaced)
        expected[f"K{k + 1}"] = res[f"K{k + 1}"]
    products = (m[:, [0, 0, 0, 1, 1, 2]] * m[:, [0, 1, 2, 1, 2, 2]]).sum(axis=0)
    expected.update(zip(("sum_m11", "sum_m12", "sum_m13", "sum_m22", "sum_m23", "sum_m33"),
                        products))
    expected.update(zip(("sum_v1", "sum_v2", "sum_v3"), rhs))
    errors = length_errors(res, solved.tol)
    coefficient = replace(solved, tol=errors["K"], relative=False)
    for key, value in expected.items():
        rules = coefficient if key.startswith("K") else solved if key.startswith("D") else None
        _run(j, key, syn.sheet, [cells[key]], [value], "-", rules)
    for key, value in eig.items():
        _run(j, key, syn.sheet, [cells[key]], [value], "rad" if key == "eig_phi" else "-",
             solved)
    if res["condition"] <= ref.SINGULAR_COND:
        # λmin = q + 2p·cos(φ + 2π/3) cancels (κ² of its terms' size), and φ = ACOS(ρ)/3 moves
        # by ρ's error over √(1 − ρ²) where two eigenvalues nearly meet (ρ near ±1)
        meet = 1.0 + 1.0 / math.sqrt(max(1.0 - half * half, EPS))
        _run(j, "condition", syn.sheet, [cells["condition"]], [res["condition"]], "-",
             replace(solved, tol=max(solved.tol,
                                     SOLVE_MARGIN * EPS * res["condition"] ** 2 * meet)))
    else:
        _beyond(j, cells["condition"], ref.SINGULAR_COND)
    a, b, c = res["a"], res["b"], res["c"]
    for key, value, unit in (("a", a, "length"), ("c", c, "length"), ("b", b, "length"),
                             ("b2", b * b if math.isfinite(b) else
                              (math.nan if singular else a * a + c * c + design.task["d"] ** 2
                               - 2 * a * c * res["K3"]), "length²")):
        _run(j, key, syn.sheet, [cells[key]], [value], unit,
             replace(solved, tol=errors[key[0]] * (2 if key == "b2" else 1)))
    _check_transmission(j, design, solved)


def _check_transmission(j, design: Design, solved) -> None:
    """The transmission angle's extremes over the input range. μ = ACOS(cos μ), and cos μ is a
    ratio of the designed lengths: their allowed relative error (the solve's bound, b's with
    its cancellation) moves cos μ by up to `spread`, and ACOS turns that into up to
    spread/sin μ, or √(2·spread) where μ is within that of 0° or 180° (acos' own modulus of
    continuity). Where a cosine lies beyond ±1 by no more than `spread` (the linkage just
    reaches a dead centre in the range), whether the loop closes there is round-off's: #N/A
    or a number."""
    syn, res = j.record.synthesis, design.result
    keys = ("mu_min", "mu_max")
    a, b, c, d = (res[k] for k in ("a", "b", "c", "d"))

    def none(dead=None) -> None:
        for key in keys:
            _run(j, key, syn.sheet, [syn.cells[key]], [math.nan], "deg", dead=dead)
    if not all(math.isfinite(v) for v in (a, b, c)) or b == 0:
        return none()
    t = design.task
    cosine = ref.transmission_cosines(a, b, c, d, *np.radians([t["theta2_start"],
                                                                t["theta2_span"]]))
    e = length_errors(res, solved.tol)
    size = a * a + b * b + c * c + d * d + 2 * abs(a) * d
    spread = (2 * (a * a * e["a"] + c * c * e["c"] + abs(a) * d * e["a"] + b * b * e["b"])
              + size * (e["b"] + e["c"])) / (2 * b * abs(c))
    if (np.abs(cosine) > 1.0 - spread).any():
        # at a dead centre to within the lengths' error: whether the loop closes there is
        # round-off's, the book's own cos μ may lie beyond ±1 (#N/A) or not
        return none(np.array([(np.abs(cosine) <= 1.0 + spread).all()]))
    for key, u in zip(keys, (cosine.max(), cosine.min())):
        near = abs(u) + spread
        moved = math.acos(max(-1.0, 1.0 - spread))
        if near < 1.0:
            moved = min(moved, spread / math.sqrt(1.0 - near * near))
        mu = math.degrees(math.acos(u))
        allowed = math.degrees(moved) + solved.tol * mu
        _run(j, key, syn.sheet, [syn.cells[key]], [mu], "deg",
             replace(solved, tol=allowed, relative=False))


def _beyond(j, cell: str, limit: float) -> None:
    """A near-singular system's condition: its digits are round-off (λmin is), so the cell
    must only say it is beyond `limit` (half of it allowed for that round-off) or be #N/A
    (λmin rounded to 0 or below)."""
    sheet = j.record.synthesis.sheet
    c = Check("synthesis", "condition", j.size)
    c.cells, value = 1, j.got(sheet, [cell])[0]
    c.judged.add((sheet, cell))
    na = j.rules.is_error(value) and j.rules.error_code(value) == "#N/A"
    if not na and not (isinstance(value, (int, float)) and value > limit / 2):
        c.mismatches.append(Mismatch(sheet, cell, f"> {limit / 2:g} or #N/A", value))
    j.checks.append(c)


def _check_words(j, design: Design) -> None:
    """The checks the sheet states in words, and its common branch; #N/A where the design
    they speak of does not exist."""
    syn, res = j.record.synthesis, design.result
    a, c = res["a"], res["c"]
    exists = math.isfinite(a) and math.isfinite(c)
    used = {float(s) for s in res["branch"] if math.isfinite(s) and s != 0}
    branches_known = bool(np.isfinite(res["branch"]).all())
    words = {
        "system": WORDS["singular"] if res["singular"] else WORDS["solvable"],
        "lengths": None if not exists else WORDS["positive"] if a > 0 and c > 0 else
        WORDS["rocker negative"] if a > 0 else WORDS["crank negative"] if c > 0 else
        WORDS["both negative"],
        "defect": None if not branches_known else
        WORDS["defect"] if res["branch_defect"] else WORDS["no defect"],
        "grashof": res["grashof"],
    }
    shown = j.got(syn.sheet, [syn.cells["grashof"]])[0]
    if exists and shown in _grashof_classes(res, length_errors(res, _solve_tol(j, design))):
        words["grashof"] = shown
    for key, text in words.items():
        _text(j, key, syn.sheet, syn.cells[key], text)
    branch = used.copy().pop() if len(used) == 1 and branches_known else math.nan
    _run(j, "branch", syn.sheet, [syn.cells["branch"]], [branch], "-")


def _solve_tol(j, design: Design) -> float:
    return solve_bound(design.result, j.record.synthesis.task["points"])


def _grashof_classes(res: dict, errors: dict) -> set[str]:
    """Grashof's classes of the lengths within their allowed errors of the design's: more than
    one only where s + l = p + q to within them (a change point, which round-off may tip)."""
    from itertools import product
    d, a, b, c = res["d"], abs(res["a"]), res["b"], abs(res["c"])
    return {grashof_class(d, a * (1 + sa * errors["a"]), b * (1 + sb * errors["b"]),
                          c * (1 + sc * errors["c"]))
            for sa, sb, sc in product((-1, 0, 1), repeat=3)}


def _text(j, key: str, sheet: str, cell: str, text: str | None) -> None:
    """A cell of words: exactly `text`, or #N/A where it is None."""
    if text is None:
        _run(j, key, sheet, [cell], [math.nan], "-")
        return
    c = Check("synthesis", key, j.size)
    compare_exact(c, sheet, [cell], j.got(sheet, [cell]), [text])
    j.checks.append(c)


def _check_designed(j, design: Design, solved) -> None:
    """The usable flag, the designed parameters' named cells and the Mechanism sheet's links
    to them."""
    syn, res = j.record.synthesis, design.result
    a, b, c = res["a"], res["b"], res["c"]
    used = {float(s) for s in res["branch"] if math.isfinite(s) and s != 0}
    if not all(math.isfinite(v) for v in (a, b, c)) or not np.isfinite(res["branch"]).all() \
            or len(used) != 1:
        usable = math.nan
    else:
        usable = bool(a > 0 and c > 0 and b > 0)
    if usable is math.nan:
        _run(j, "usable", syn.sheet, [syn.cells["usable"]], [usable], "-")
    else:                                   # TRUE or FALSE
        check = Check("synthesis", "usable", j.size)
        compare_exact(check, syn.sheet, [syn.cells["usable"]],
                      j.got(syn.sheet, [syn.cells["usable"]]), [usable])
        j.checks.append(check)
    errors = length_errors(res, solved.tol)
    for role, symbol in syn.task["designs"].items():
        value = design.designed[symbol]
        unit = "-" if role == "branch" else "length"
        rules = None if role == "branch" else replace(solved, tol=errors[
            {"crank": "a", "coupler": "b", "rocker": "c"}[role]])
        _run(j, f"designed {symbol}", syn.sheet, [syn.cells[f"designed_{role}"]], [value],
             unit, rules)
        _run(j, f"link to {symbol}", "Mechanism", [j.record.inputs[symbol].cell], [value],
             unit, rules)


def _generated(j, design: Design, theta2_deg: np.ndarray) -> np.ndarray:
    """The rocker's angle (radians) of the designed linkage (as_designed) at these crank
    angles, by the kinematic reference; NaN throughout where nothing is designed."""
    if not design.usable:
        return np.full(len(theta2_deg), math.nan)
    return np.asarray(j.solver.solve(j.params, np.asarray(theta2_deg, dtype=float))[
        j.record.synthesis.task["output"]], dtype=float)


def _wrapped(degrees: np.ndarray) -> np.ndarray:
    return (np.asarray(degrees, dtype=float) + 180.0) % 360.0 - 180.0


def _marked(j, sheet: str, cells: list[str], shown: list) -> None:
    """A column that marks one row with its number and the others with a dash (or #N/A
    throughout, NaN)."""
    if all(isinstance(v, float) and math.isnan(v) for v in shown):
        _run(j, "error table at_largest", sheet, cells, shown, "-")
        return
    c = Check("synthesis", "error table at_largest", j.size)
    compare_exact(c, sheet, cells, j.got(sheet, cells), shown)
    j.checks.append(c)


def _check_error_table(j, design: Design) -> None:
    """The structural error table over the input range, its largest error and where."""
    syn = j.record.synthesis
    t = design.task
    steps = len(syn.error["x"]) - 1
    k = np.arange(steps + 1)
    x = t["x0"] + k * (t["x1"] - t["x0"]) / steps
    theta2 = t["theta2_start"] + k * t["theta2_span"] / steps
    f = f_of(j.record)
    y = f(x)
    desired = t["theta4_start"] + (y - t["f_x0"]) / (t["f_x1"] - t["f_x0"]) * t["theta4_span"]
    generated = _generated(j, design, theta2)
    error = _wrapped(np.degrees(generated) - desired)
    slopes = _output_slopes(j, theta2)
    expected = {"x": x, "theta2_deg": theta2, "y": y, "desired": desired,
                "generated": generated, "error": error}
    units = {"x": "-", "theta2_deg": "deg", "y": "-", "desired": "deg", "generated": "rad",
             "error": "deg"}
    if np.isfinite(error).all():
        at = int(np.argmax(np.abs(error)))
        largest, where = float(abs(error[at])), float(x[at])
    else:
        largest = where = math.nan
    for key, cells in syn.error.items():
        if key == "at_largest":        # x on the largest error's row, a dash elsewhere
            shown = [float(x[k]) if k == at else DASH for k in range(len(x))] \
                if math.isfinite(largest) else [math.nan] * len(x)
            _marked(j, syn.sheet, list(cells), shown)
            continue
        _run(j, f"error table {key}", syn.sheet, list(cells), expected[key], units[key],
             slope=slopes.get(key))
    _run(j, "largest error", syn.sheet, [syn.cells["largest_error"]], [largest], "deg")
    _run(j, "largest error at x", syn.sheet, [syn.cells["largest_error_x"]], [where], "-")
