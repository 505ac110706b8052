"""Judging the Synthesis sheet of motion and path generation (docs/synthesis.md): the task read
from the book's own cells, the four-bar designed by the independent reference
(reference/synthesis_motion.py, which finds the pivots themselves, never by the standard
form), every cell of the sheet compared with it, and the designed values handed to the
kinematic and force references, which judge the analysis sheets as for any book.

A cell the standard form defines by its own terms (the coefficients e^{iρ} − 1, D, Cramer's
numerators, the singular values behind cond₂) is computed here by numpy's complex arithmetic
and SVD from the task; every result (W, Z, U, S, the pivots, the lengths, the coupler point,
the angles at each pose, the branch, Grashof's class) is the reference's.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..base.record import BuildRecord
from ..base.sheets import SYNTHESIS_WORDS as WORDS
from .checks import ABS_TOL, PER, Check, Mismatch, Rules, compare_exact
from .reference import synthesis_motion as ref
from .reference.fourbar import grashof_class

EPS = float(np.finfo(float).eps)
# the solve's bound relative to the task's size: SOLVE_MARGIN·ε·κ (κ the larger of the two
# dyads' cond₂), never below the 1e-9 of any other cell; as check/synthesis.py's for three
# precision points, where the margin covers the constant of Cramer's rule on a 2×2
SOLVE_MARGIN = 1000.0


@dataclass
class DyadDesign:
    """The task as the book holds it and the reference's design of it."""
    points: np.ndarray          # P_j, complex
    alpha: np.ndarray           # the coupler's angles, radians (a path's α_1 = 0)
    rotations: dict             # {"crank": [0, β2, β3], "rocker": [0, γ2, γ3]}, radians
    result: dict                # reference.synthesis_motion.motion_generation's
    dyads: dict                 # {"crank"|"rocker": (condition, G, M)}: G, M NaN if singular
    designed: dict              # {symbol: value} of the designed parameters (NaN: none)

    @property
    def exists(self) -> bool:
        return not (self.result["singular"] or self.result["degenerate"])


def _complex_nan() -> complex:
    return complex(math.nan, math.nan)


def design_for(record: BuildRecord, inputs: dict[str, float]) -> DyadDesign:
    """The reference's design of the record's task with these inputs (the Synthesis sheet's
    input cells by key: x1 … y3, alpha1 … alpha3 or alpha2, alpha3, beta2 … gamma3)."""
    spec = record.synthesis.task
    x = [inputs[f"x{j}"] for j in (1, 2, 3)]
    y = [inputs[f"y{j}"] for j in (1, 2, 3)]
    alpha = np.radians([inputs.get("alpha1", 0.0), inputs["alpha2"], inputs["alpha3"]])
    points = np.array(x) + 1j * np.array(y)
    turn = alpha - alpha[0]
    given, dyads, rotations = {}, {}, {}
    for dyad, key in (("crank", "beta"), ("rocker", "gamma")):
        if f"{dyad}_x" in inputs:           # its fixed pivot given (Norton §5.9)
            fixed = complex(inputs[f"{dyad}_x"], inputs[f"{dyad}_y"])
            moving, condition = ref.dyad_from_fixed_pivot(points, turn, fixed)
            given[f"{dyad}_pivot"] = (fixed.real, fixed.imag)
            dyads[dyad] = (condition, fixed, moving)
            # its rotations are results: the moving pivot carried by the coupler, about G
            carried = points + np.exp(1j * turn) * (moving - points[0])
            rotations[dyad] = np.angle((carried - fixed) / (moving - fixed))
            continue
        rotation = np.radians([0.0, inputs[f"{key}2"], inputs[f"{key}3"]])
        given[f"{dyad}_rotation"] = rotation[1:]
        condition = ref.standard_form_condition(turn, rotation)
        pivots = ref.dyad_from_rotations(points, turn, rotation) \
            if condition <= ref.SINGULAR_COND else None
        dyads[dyad] = (condition, *(pivots or (_complex_nan(), _complex_nan())))
        rotations[dyad] = rotation
    result = ref.motion_generation(x, y, alpha, **given)
    return DyadDesign(points, alpha, rotations, result, dyads,
                      _designed(result, spec["designs"]))


def _values(result: dict) -> dict[str, float]:
    """{role: value} of the reference's four-bar."""
    (u, v), (xa, ya), (xb, yb) = result["coupler_point"], result["A0"], result["B0"]
    return {"crank": result["a"], "coupler": result["b"], "rocker": result["c"],
            "ground": result["d"], "u": u, "v": v,
            "offset": math.degrees(result["coupler_offset"]), "xA0": xa, "yA0": ya,
            "xB0": xb, "yB0": yb}


def _common_branch(result: dict) -> float:
    """The branch every pose is on (dead centres aside), NaN where there is none."""
    used = {float(s) for s in result["branch"] if math.isfinite(s) and s != 0}
    return used.pop() if len(used) == 1 else math.nan


def _designed(result: dict, designs: dict) -> dict[str, float]:
    """What the book's designed cells must hold: the four-bar on one branch at every pose;
    else NaN (#N/A) for every one."""
    branch = _common_branch(result)
    values = {**_values(result), "branch": branch}
    usable = math.isfinite(branch) and all(math.isfinite(v) for v in values.values())
    return {symbol: values[role] if usable else math.nan for role, symbol in designs.items()}


def with_design(record: BuildRecord, values: dict[str, float], inputs: dict[str, float]
                ) -> dict[str, float]:
    """`values` with the designed parameters' values: the reference's design of the task with
    these `inputs`."""
    designed = design_for(record, inputs).designed
    branch = record.synthesis.task["designs"]["branch"]
    if math.isnan(designed[branch]):
        designed[branch] = 1.0      # no linkage: every analysis cell #N/A on either branch
    return {**values, **designed}


def no_design_because(result: dict) -> str | None:
    """Why the reference's design is no linkage to analyse, in words; None where it is one."""
    if result["singular"]:
        return "a dyad's system is near-singular"
    if result["degenerate"]:
        return "a link of (almost) zero length"
    if result["branch_defect"]:
        return "a branch defect"
    if not math.isfinite(_common_branch(result)):
        return "a dead centre at every pose"
    return None


def task_table(spec: dict, inputs: dict[str, float]) -> dict:
    """The [synthesis] table of the record's task with these inputs (the language checks it:
    input_sets keeps a moved task only where it is one the language accepts)."""
    pairs = [[inputs[f"x{j}"], inputs[f"y{j}"]] for j in (1, 2, 3)]
    table = {"kind": spec["kind"], "designs": spec["designs"]}
    for dyad, key in (("crank", "beta"), ("rocker", "gamma")):
        if f"{dyad}_x" in inputs:
            table.setdefault("pivots", {})[dyad] = [inputs[f"{dyad}_x"], inputs[f"{dyad}_y"]]
        else:
            table[key] = [inputs[f"{key}2"], inputs[f"{key}3"]]
    if spec["kind"] == "motion":
        return {**table, "poses": [p + [inputs[f"alpha{j}"]] for j, p in enumerate(pairs, 1)]}
    return {**table, "points": pairs, "alpha": [inputs["alpha2"], inputs["alpha3"]]}


# ---------------------------------------------------------------- the bounds
def solve_bound(design: DyadDesign) -> float:
    """The relative bound of the solve's cells (SOLVE_MARGIN·ε·κ, at least 1e-9)."""
    kappa = max((c for c, _, _ in design.dyads.values() if math.isfinite(c)), default=1.0)
    return max(ABS_TOL, SOLVE_MARGIN * EPS * min(kappa, ref.SINGULAR_COND))


def task_size(design: DyadDesign) -> float:
    """L: the largest coordinate or length of the task and its pivots, the scale of every
    length's bound."""
    sizes = [*np.abs(design.points)]
    for _, g, m in design.dyads.values():
        sizes += [abs(g), abs(m), abs(m - g)]
    finite = [s for s in sizes if math.isfinite(s)]
    return max(finite + [1e-300])


def _lever(design: DyadDesign) -> float:
    """How much an angle or a position measured off the shortest link magnifies the bound:
    L over the shortest of a, b, c (1 where there is no four-bar)."""
    res = design.result
    shortest = min((res[k] for k in "abc" if math.isfinite(res[k]) and res[k] > 0),
                   default=0.0)
    return max(1.0, task_size(design) / shortest) if shortest > 0 else 1.0


def as_designed(record: BuildRecord, inputs: dict[str, float], values: dict, params: dict
                ) -> dict[str, float]:
    """The parameters the analysis sheets are judged with: the book's designed values where
    they agree with the reference's design of the task's `inputs` within the solve's bound
    (so the kinematic and force references analyse the linkage the book designed); the
    reference's where they do not."""
    syn = record.synthesis
    design = design_for(record, inputs)
    bound = solve_bound(design) * _lever(design)
    size = task_size(design)
    out = dict(params)
    for role, symbol in syn.task["designs"].items():
        want, got = params[symbol], values.get((syn.sheet, syn.cells[f"designed_{role}"]))
        scale = 180.0 / math.pi if role == "offset" else size if role != "branch" else 0.0
        if isinstance(got, (int, float)) and not isinstance(got, bool) and \
                math.isfinite(want) and abs(got - want) <= bound * scale:
            out[symbol] = float(got)
    return out


# ---------------------------------------------------------------- the checks
class _Judge:
    """The sheet's cells against their expected values, with the bounds of this design."""

    def __init__(self, j, design: DyadDesign):
        self.j, self.design = j, design
        self.sheet = j.record.synthesis.sheet
        self.cells, self.columns = j.record.synthesis.cells, j.record.synthesis.points
        self.bound, self.size = solve_bound(design), task_size(design)
        self.lever = _lever(design)

    def run(self, name: str, cells: list[str], expected, unit: str, lever: float = 1.0,
            sheet: str | None = None) -> None:
        """`cells` against `expected`: a length within bound·L (times `lever`), an area
        within bound·L², an angle (degrees) within the bound in radians over the shortest
        link, a ratio within the bound."""
        tol = self.bound * lever
        scale = {"length": self.size * PER, "length²": self.size ** 2 * PER}.get(unit)
        if unit == "deg":
            tol = math.degrees(tol)
        c = Check("synthesis", name, self.j.size, 1.0, scale)
        rules = Rules(self.j.rules.is_error, self.j.rules.error_code, tol, False)
        self.j.compare(c, sheet or self.sheet, list(cells), np.asarray(expected, dtype=float),
                       unit, rules=rules)
        self.j.checks.append(c)

    def cell(self, key: str, expected: float, unit: str, lever: float = 1.0) -> None:
        self.run(key, [self.cells[key]], [expected], unit, lever)

    def text(self, key: str, expected) -> None:
        """A cell of words or TRUE/FALSE: exactly `expected`, or #N/A where it is None."""
        if expected is None:
            self.run(key, [self.cells[key]], [math.nan], "-")
            return
        c = Check("synthesis", key, self.j.size)
        compare_exact(c, self.sheet, [self.cells[key]],
                      self.j.got(self.sheet, [self.cells[key]]), [expected])
        self.j.checks.append(c)


def check_synthesis(j, inputs: dict[str, float]) -> np.ndarray:
    """Every cell of the Synthesis sheet but its drawing, and the Mechanism sheet's links to
    the designed cells, against the reference's design of the task's `inputs`
    (j: context.Judging). Returns the reference's crank angle at each pose, in degrees."""
    design = design_for(j.record, inputs)
    judge = _Judge(j, design)
    _check_poses(judge)
    for dyad in ("crank", "rocker"):
        about_pivot = f"{dyad}_x" in inputs
        (_check_dyad_about_pivot if about_pivot else _check_dyad)(judge, dyad)
    _check_four_bar(judge)
    _check_at_poses(judge)
    _check_words(judge)
    _check_designed(judge)
    return np.degrees(np.asarray(design.result["theta2"], dtype=float))


def _minus_one(angles) -> np.ndarray:
    return np.exp(1j * np.asarray(angles, dtype=float)) - 1.0


def _check_poses(judge: _Judge) -> None:
    d = judge.design
    turn = d.alpha - d.alpha[0]
    delta = d.points - d.points[0]
    crank, rocker = d.rotations["crank"], d.rotations["rocker"]
    expected = {"turn": np.degrees(turn), "beta": np.degrees(crank),
                "gamma": np.degrees(rocker), "dx": delta.real, "dy": delta.imag}
    for part, angles in (("b", crank), ("c", turn), ("g", rocker)):
        expected[f"{part}_re"] = _minus_one(angles).real
        expected[f"{part}_im"] = _minus_one(angles).imag
    for key, value in expected.items():
        unit = "deg" if key in ("turn", "beta", "gamma") else \
            "length" if key in ("dx", "dy") else "-"
        judge.run(f"pose {key}", judge.columns[f"pose_{key}"], value, unit)


def _check_dyad(judge: _Judge, dyad: str) -> None:
    """D, the numerators, F, t₁, t₂, cond₂ and the words by numpy; the solution (the dyad's
    two vectors at pose 1) the reference's: W = A − A0, Z = P_1 − A (U, S for the rocker)."""
    d = judge.design
    k, (first, second) = dyad[0], (("W", "Z") if dyad == "crank" else ("U", "S"))
    turn = d.alpha - d.alpha[0]
    b, c = _minus_one(d.rotations[dyad][1:]), _minus_one(turn[1:])
    delta = (d.points - d.points[0])[1:]
    det = b[0] * c[1] - b[1] * c[0]
    numerators = {first: delta[0] * c[1] - delta[1] * c[0],
                  second: b[0] * delta[1] - b[1] * delta[0]}
    sigma = np.linalg.svd(np.column_stack([b, c]), compute_uv=False)
    condition, g, m = d.dyads[dyad]
    for key, value in (("D_re", det.real), ("D_im", det.imag), ("D2", abs(det) ** 2),
                       ("F", float(np.sum(sigma ** 2))), ("t1", sigma[0] ** 2),
                       ("t2", sigma[1] ** 2)):
        judge.cell(f"{k}_{key}", value, "-")
    for v, value in numerators.items():
        judge.cell(f"{k}_N{v}_re", value.real, "length")
        judge.cell(f"{k}_N{v}_im", value.imag, "length")
    _judge_system(judge, k, condition, {first: m - g, second: d.points[0] - m})


def _judge_system(judge: _Judge, k: str, condition: float, vectors: dict[str, complex]
                  ) -> None:
    """A dyad's condition number (or that it lies beyond the limit), its system in words, and
    its two vectors (W and Z, or U and S) by parts."""
    if condition <= ref.SINGULAR_COND:
        judge.cell(f"{k}_condition", condition, "-", lever=condition)
    else:
        _beyond(judge, f"{k}_condition", ref.SINGULAR_COND)
    judge.text(f"{k}_system", WORDS["singular" if condition > ref.SINGULAR_COND
                                   else "solvable"])
    for v, vector in vectors.items():
        judge.cell(f"{v}_x", vector.real, "length")
        judge.cell(f"{v}_y", vector.imag, "length")


def _check_dyad_about_pivot(judge: _Judge, dyad: str) -> None:
    """The circle condition's rows, right-hand sides and determinant, its solution m and
    the singular values behind its condition by numpy; the condition, W and Z (U and S) and
    the dyad's rotations, now results, the reference's."""
    d = judge.design
    k, key = dyad[0], ("beta" if dyad == "crank" else "gamma")
    first, second = ("W", "Z") if dyad == "crank" else ("U", "S")
    condition, g, m = d.dyads[dyad]
    turn = d.alpha - d.alpha[0]
    rows, rhs = ref.circle_condition(d.points, turn, g)
    first_arm = d.points[0] - g
    judge.cell(f"{k}_e1_x", first_arm.real, "length")
    judge.cell(f"{k}_e1_y", first_arm.imag, "length")
    for j in (2, 3):
        judge.cell(f"{k}_row{j}_x", rows[j - 2, 0], "length")
        judge.cell(f"{k}_row{j}_y", rows[j - 2, 1], "length")
        judge.cell(f"{k}_rhs{j}", rhs[j - 2], "length²")
    det = float(np.linalg.det(rows))
    sigma = np.linalg.svd(rows, compute_uv=False)
    solution = np.linalg.solve(rows, rhs) if det != 0 else np.full(2, math.nan)
    judge.cell(f"{k}_det", det, "length²")
    judge.cell(f"{k}_mx", solution[0], "length", lever=min(condition, ref.SINGULAR_COND))
    judge.cell(f"{k}_my", solution[1], "length", lever=min(condition, ref.SINGULAR_COND))
    for name, value in (("F", float(np.sum(sigma ** 2))), ("t1", sigma[0] ** 2),
                        ("t2", sigma[1] ** 2)):
        judge.cell(f"{k}_{name}", value, "length²")
    _judge_system(judge, k, condition, {first: m - g, second: d.points[0] - m})
    for j in (2, 3):
        judge.cell(f"{key}{j}", math.degrees(d.rotations[dyad][j - 1]), "deg", judge.lever)


def _beyond(judge: _Judge, key: str, limit: float) -> None:
    """A near-singular system's condition: its digits are round-off, so the cell must only
    say it is beyond `limit` (half of it allowed for that round-off) or be #N/A."""
    j, cell = judge.j, judge.cells[key]
    c = Check("synthesis", key, j.size)
    c.cells, value = 1, j.got(judge.sheet, [cell])[0]
    c.judged.add((judge.sheet, cell))
    na = j.rules.is_error(value) and j.rules.error_code(value) == "#N/A"
    if not na and not (isinstance(value, (int, float)) and value > limit / 2):
        c.mismatches.append(Mismatch(judge.sheet, cell, f"> {limit / 2:g} or #N/A", value))
    j.checks.append(c)


def _check_four_bar(judge: _Judge) -> None:
    """The pivots and lengths from each dyad's pivots (numbers even where the four-bar is
    degenerate: the sheet shows them, and says why nothing is designed), then what needs a
    four-bar: the coupler point and offset, the reference's."""
    d, res = judge.design, judge.design.result
    (_, a0, a1), (_, b0, b1) = d.dyads["crank"], d.dyads["rocker"]
    for point, z in (("A", a1), ("A0", a0), ("B", b1), ("B0", b0)):
        judge.cell(f"x{point}", z.real, "length")
        judge.cell(f"y{point}", z.imag, "length")
    lengths = {"a": abs(a1 - a0), "b": abs(b1 - a1), "c": abs(b1 - b0), "d": abs(b0 - a0)}
    for key, value in lengths.items():
        judge.cell(key, value, "length")
    deltas = np.abs(d.points[1:] - d.points[0])
    size = max(*lengths.values(), *deltas)      # NaN where a dyad is singular
    judge.cell("size", size if all(map(math.isfinite, lengths.values())) else math.nan,
               "length")
    solvable = all(c <= ref.SINGULAR_COND for c, _, _ in d.dyads.values())
    judge.text("exists", bool(solvable and not res["degenerate"]))
    judge.text("short", None if not solvable else
               WORDS["too short" if res["degenerate"] else "long enough"])
    u, v = res["coupler_point"]
    judge.cell("u", u, "length", judge.lever)
    judge.cell("v", v, "length", judge.lever)
    judge.cell("offset", math.degrees(res["coupler_offset"]), "deg", judge.lever)


def _check_at_poses(judge: _Judge) -> None:
    """The designed linkage at each pose: its angles, branch and transmission angle the
    reference's; the coupler point and angle the position steps give, the kinematic
    reference's at the designed parameters (NaN where nothing is designed)."""
    d, res, j = judge.design, judge.design.result, judge.j
    theta2, theta3, theta4 = (np.asarray(res[k], dtype=float)
                              for k in ("theta2", "theta3", "theta4"))
    a0, b0 = complex(*res["A0"]), complex(*res["B0"])
    reach = a0 - b0 + res["a"] * np.exp(1j * theta2)
    rocker = res["c"] * np.exp(1j * theta4)
    mu = np.arccos(np.cos(theta3 - theta4))
    columns = judge.columns
    for key, value, unit, lever in (
            ("theta2", np.degrees(theta2), "deg", judge.lever),
            ("theta4", np.degrees(theta4), "deg", judge.lever),
            ("cross", (np.conj(rocker) * reach).imag, "length²", judge.lever),
            ("branch", res["branch"], "-", 1.0),
            ("mu", np.degrees(mu), "deg", judge.lever)):
        judge.run(f"at pose {key}", columns[f"at_{key}"], value, unit, lever)
    offset = math.degrees(res["coupler_offset"])
    if all(math.isfinite(v) for v in d.designed.values()):
        placed = j.solver.solve(j.params, np.asarray(_crank_angles(judge)))
        keys = j.record.synthesis.task["keys"]
        x, y = (np.asarray(placed[keys[k]], dtype=float) for k in ("x", "y"))
        angle = np.degrees(np.asarray(placed[keys["theta3"]], dtype=float)) + offset
    else:
        x = y = angle = np.full(3, math.nan)
    miss_angle = (angle - np.degrees(d.alpha) + 180.0) % 360.0 - 180.0
    for key, value, unit in (("x", x, "length"), ("y", y, "length"), ("angle", angle, "deg"),
                             ("miss_x", x - d.points.real, "length"),
                             ("miss_y", y - d.points.imag, "length"),
                             ("miss_angle", miss_angle, "deg")):
        judge.run(f"at pose {key}", columns[f"at_{key}"], value, unit, judge.lever)
    judge.cell("largest_miss", float(np.max(np.abs(x + 1j * y - d.points))), "length",
               judge.lever)
    judge.cell("largest_angle_miss", float(np.max(np.abs(miss_angle))), "deg", judge.lever)


def _crank_angles(judge: _Judge) -> list[float]:
    """The crank angles (degrees) the book places the designed linkage at: its own θ2_j
    cells where they hold numbers (judged above against the reference), else the
    reference's."""
    got = judge.j.got(judge.sheet, list(judge.columns["at_theta2"]))
    want = np.degrees(np.asarray(judge.design.result["theta2"], dtype=float))
    return [float(g) if isinstance(g, (int, float)) and not isinstance(g, bool) else float(w)
            for g, w in zip(got, want)]


def _check_words(judge: _Judge) -> None:
    """The branch defect, the common branch, Grashof's class and the transmission angle's
    range: #N/A where the four-bar they speak of does not exist."""
    res = judge.design.result
    known = bool(np.isfinite(res["branch"]).all())
    judge.text("defect", None if not known else
               WORDS["defect" if res["branch_defect"] else "no defect"])
    judge.cell("branch", _common_branch(res) if known else math.nan, "-")
    exists = judge.design.exists
    judge.text("grashof", grashof_class(res["d"], res["a"], res["b"], res["c"])
               if exists else None)
    mu = np.degrees(np.arccos(np.cos(np.asarray(res["theta3"]) - np.asarray(res["theta4"]))))
    judge.cell("mu_min", float(np.min(mu)) if exists else math.nan, "deg", judge.lever)
    judge.cell("mu_max", float(np.max(mu)) if exists else math.nan, "deg", judge.lever)


def _check_designed(judge: _Judge) -> None:
    """The usable flag (FALSE without a four-bar, #N/A without a common branch), the designed
    parameters' named cells and the Mechanism sheet's links to them."""
    d, j = judge.design, judge.j
    branch = _common_branch(d.result)
    judge.text("usable", (True if math.isfinite(branch) else None) if d.exists else False)
    for role, symbol in j.record.synthesis.task["designs"].items():
        value = d.designed[symbol]
        unit = "-" if role == "branch" else "deg" if role == "offset" else "length"
        lever = judge.lever if role in ("u", "v", "offset") else 1.0
        judge.cell(f"designed_{role}", value, unit, lever)
        judge.run(f"link to {symbol}", [j.record.inputs[symbol].cell], [value], unit, lever,
                  sheet="Mechanism")
