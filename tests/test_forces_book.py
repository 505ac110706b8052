"""The Forces sheet of built books (issue 31), read as a user reads it: the cells the force
writer's formulas compute, evaluated by the vector engine. Every expected value comes from outside
the writer: the numbers Marghitu printed (and those derived by hand from his data), the
independent Newton–Euler reference through verify, the power balance with the velocities of the
independent kinematic reference, and two cases solved by hand. The templates are in
tests/data/forces/: one mechanism of each family the writer supports, every mass, inertia,
centre, load and the gravity a parameter, so that the random tests can draw them."""
from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from conftest import checks_of, examples, formula_cells, published
from si_motion import SIMotion, inline_piston
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.engine import evaluator as engine
from linkbook.language import templates
from linkbook.language.mechanisms import ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, OFFSET_KIND
from test_properties import dimensions, in_load_domain
from test_properties import with_values as dimensioned

EXAMPLES = examples(40, at_least=3)     # three: each family still has rows to balance
# What the random test found, kept whatever the number of examples drawn: family -> the drawn
# values. The inverted slider-crank with only the block's mass, no gravity, the crank at a
# constant speed: the block's acceleration is across its path, every power term is rounding.
FOUND = {
    "inverted-slider-crank": {
        "a1": 100.0, "a2": 40.0, "a4": 30.0, "branch": 1.0, "u2": 15.0, "v2": 2.0, "d4": 45.0,
        "phi4": 0.0, "g_angle": 0.0, "omega_in": 10.0, "alpha_in": 0.0, "m2": 0.0, "I2": 0.0,
        "m3": 1.0, "I3": 0.0, "m4": 0.0, "I4": 0.0, "FAx": 0.0, "FAy": 0.0, "T4": 0.0,
        "g": 0.0},
}
DATA = Path(__file__).resolve().parent / "data" / "forces"
FAMILIES = ["fourbar", "slider-crank", "toggle-press", "boom-cylinder", "watt-sixbar",
            "inverted-slider-crank", "pump", "rocker-block"]
METRES = {"mm": 1e-3, "cm": 1e-2, "m": 1.0}
SHEET = "Forces"


def load(name: str) -> templates.Template:
    return templates.load(str(DATA / f"{name}.toml"))


def with_values(t: templates.Template, **values) -> templates.Template:
    """The template with some parameters' values replaced."""
    unknown = set(values) - {p.symbol for p in t.parameters}
    assert not unknown, unknown
    return dataclasses.replace(t, parameters=tuple(
        dataclasses.replace(p, value=values.get(p.symbol, p.value)) for p in t.parameters))


def forces_row(built, values, row: int) -> dict:
    """{quantity: the computed cell} of one row of the Forces sheet."""
    columns = built.meta["forces"]["columns"]
    return {key: values[(SHEET, f"{letter}{row}")] for key, letter in columns.items()}


def row_of(built, values, value: float) -> int:
    """The Forces row of the sweep whose input is `value`."""
    first, last = built.meta["forces"]["rows"]
    for r in range(first, last + 1):
        if abs(values[(SHEET, f"A{r}")] - value) < 1e-9:
            return r
    raise KeyError(value)


def assert_verified(built, values) -> None:
    """Every formula cell judged, none out of verify's bounds (#N/A exactly where the reference
    has no value)."""
    checks = checks_of(built, values)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches]
    assert not bad, bad[:6]
    assert sum(c.cells for c in checks) == len(formula_cells(built.workbook))
    assert any(c.block == SHEET for c in checks)


# --------------------------------------------------------------------------------------------
# 1. Marghitu's published slider-crank
# --------------------------------------------------------------------------------------------

def marghitu_template() -> templates.Template:
    """tests/data/forces/marghitu.toml with the book's inputs (published.toml)."""
    i = published()["marghitu_slider_crank_forces"]["inputs"]
    t = with_values(load("marghitu"), AB=i["AB"], BC=i["BC"], m1=i["m1"], m2=i["m2"],
                    m3=i["m3"], I1=i["I1"], I2=i["I2"], I3=i["I3"], g=i["g"],
                    F_ext=i["F_ext"], omega_in=i["omega"], alpha_in=i["alpha"])
    assert t.position == i["phi"]
    return t


def marghitu_book():
    return published()["marghitu_slider_crank_forces"], builder.make(marghitu_template())


def test_marghitu_published_at_the_current_position_and_on_the_sweep():
    """Marghitu (2009), p. 144: F12, the crank's force on the rod at B, printed as closed forms.
    The book numbers the links from 0 (the ground); ours from 1, so his F12 is our F23."""
    case, (built, values) = marghitu_book()
    phi = case["inputs"]["phi"]
    for row in (built.meta["forces"]["current_row"], row_of(built, values, phi)):
        got = forces_row(built, values, row)
        for book, ours in (("F12x", "F23x"), ("F12y", "F23y")):
            assert got[ours] == pytest.approx(case["published"][book],
                                              rel=case["rel_tolerance"]), (row, ours)


def test_marghitu_derived_unknowns():
    """The example's other unknowns, solved by hand from the book's data link by link (each
    link's ΣF and ΣM: derived, not printed; see test_force_reference.py), in the book's
    numbering F01 → our F12, F23 → F34, F03 → F14, M → T12. The shaking force is what the links
    push the ground with, −(F01 + F03); its moment about A, −M − r_C × F03."""
    case, (built, values) = marghitu_book()
    r2 = math.sqrt(2.0)
    derived = {"T12": 3 + 105 * r2, "F12x": -100 - 2 * r2, "F12y": 115 + r2,
               "F34x": -100 - r2, "F34y": 95 + 1.5 * r2, "F14x": 0.0, "F14y": -85 - 1.5 * r2,
               "N14": -85 - 1.5 * r2, "shaking_x": 100 + 2 * r2,
               "shaking_y": -30 + r2 / 2, "shaking_moment": -20 * r2}
    for row in (built.meta["forces"]["current_row"],
                row_of(built, values, case["inputs"]["phi"])):
        got = forces_row(built, values, row)
        for key, want in derived.items():
            assert got[key] == pytest.approx(want, rel=1e-9, abs=1e-9), (row, key)


def test_marghitu_book_verifies_and_balances_power():
    _, (built, values) = marghitu_book()
    assert_verified(built, values)
    assert assert_power_balance(marghitu_template(), built, values) > 0


def test_marghitu_book_at_the_rod_square_to_the_guide():
    """The same book swept in steps of 15°, through 90° and 270°, where the slider meets the
    crank's pivot and the rod is perpendicular to the guide: the group of rod and slider cannot
    carry the slider's load there. The reference finds its equations singular; the book's
    determinant is cos 90° ≈ 6e-17 in rounding, not 0, so it shows a huge number: verify takes
    #N/A or a number there (not determined by the data, as a rate at a dead centre), and judges
    every other row as usual."""
    t = dataclasses.replace(marghitu_template(), sweep=templates.Sweep(0.0, 360.0, 15.0))
    assert_verified(*builder.make(t))


def test_guide_force_component_where_the_loop_cannot_close():
    """The slider-crank with its guide 270 mm off the crank's pivot, out of reach of the rod
    (250 mm) near θ = 0° and 180°: no position there, so no force either (every force and
    moment #N/A; the crank's centre of mass is where the crank is, whatever the rest does)."""
    built, values = builder.make(with_values(load("slider-crank"), a1=270.0))
    row = row_of(built, values, 0.0)
    got = {k: v for k, v in forces_row(built, values, row).items()
           if not k.startswith(("xG2", "yG2", "axG2", "ayG2"))}
    assert got and all(engine.is_error(v) for v in got.values()), \
        {k: v for k, v in got.items() if not engine.is_error(v)}


# --------------------------------------------------------------------------------------------
# 2 and 3. Random mechanisms, masses and loads: verify, and the power balance on the book
# --------------------------------------------------------------------------------------------

def placement_symbols(t: templates.Template) -> set[str]:
    """The parameters the masses, loads and gravity name (not the steps')."""
    d = t.mechanism.description
    return set(re.findall(r"[A-Za-z_]\w*", repr([d.get(k) for k in ("dynamics", "bodies",
                                                                       "loads")])))


def near(t: templates.Template):
    """Lengths 0.9 to 1.1 times the template's, offsets within a twentieth of its size of their
    own, the steps' angles within 10° and the branches as written: mechanisms that mostly
    assemble, so that most rows have forces to judge (with the dimensions of test_properties,
    0.2 to 3 times and any angle, few six-bars close on more than a row or two)."""
    scale = max(abs(p.value) for p in t.parameters if p.kind == LENGTH_KIND)
    placing = placement_symbols(t)
    draws = {}
    for p in t.parameters:
        if p.kind == LENGTH_KIND:
            draws[p.symbol] = st.floats(0.9, 1.1).map(lambda f, v=p.value: f * v)
        elif p.kind == OFFSET_KIND:
            draws[p.symbol] = st.floats(-0.05, 0.05).map(lambda f, v=p.value: v + f * scale)
        elif p.kind == ANGLE_KIND and p.symbol not in placing:
            draws[p.symbol] = st.floats(-10.0, 10.0).map(lambda f, v=p.value: v + f)
        elif p.kind == BRANCH_KIND:
            draws[p.symbol] = st.just(p.value)
    return st.fixed_dictionaries(draws)


def dynamics(t: templates.Template):
    """Dimensions as test_properties draws them (any angle, branch and rate) or, every other
    example, near the template's (`near`); masses 0..10 kg, inertias 0..0.1 kg·m², forces
    ±1e3 N, torques ±100 N·m, gravity off or 0..20 m/s² (its direction an angle parameter)."""
    kinds = {kind: values.filter(in_load_domain) for kind, values in (
        ("mass", st.floats(0.0, 10.0)), ("inertia", st.floats(0.0, 0.1)),
        ("force", st.floats(-1e3, 1e3)), ("torque", st.floats(-100.0, 100.0)),
        ("acceleration", st.one_of(st.just(0.0), st.floats(0.0, 20.0))))}
    kinematic = dataclasses.replace(t, parameters=tuple(p for p in t.parameters
                                                        if p.kind not in kinds))
    draws = {p.symbol: kinds[p.kind] for p in t.parameters if p.kind in kinds}
    return st.tuples(dimensions(kinematic), st.booleans(), near(kinematic),
                     st.fixed_dictionaries(draws)).map(
        lambda d: {**d[0], **(d[2] if d[1] else {}), **d[3]})


def guides(description: dict) -> dict[str, tuple[str, str]]:
    """The blocks on a moving line, by their point: the two points of the link they slide on
    and turn with (a slide's block at p: its line, point→p; a slider's along a link: that link;
    the pin in a vector step's slotted link: its frame from→to).
    A block on a fixed line does not turn."""
    out = {}
    for step in description["steps"]:
        if step["type"] == "slide":     # its line N→P turns with it (N is the pivot at offset 0)
            out[step["p"]] = (step["point"], step["p"])
        elif step["type"] == "slider" and "along" in step:
            out[step["point"]] = tuple(step["along"])
        elif step["type"] == "vector":      # a slotted link's pin (where a block names it)
            out[step["to"]] = (step["from"], step["to"])
    return out


class Motion(SIMotion):
    """The kinematic reference's motion at the given inputs, in SI units."""

    def __init__(self, t: templates.Template, params: dict, inputs):
        super().__init__(solve(t.mechanism.description, params, np.asarray(inputs, dtype=float)),
                         METRES[t.length_unit])
        self.guides = guides(t.mechanism.description)

    def centre(self, entry: dict, number):
        """The centre of mass's velocity and acceleration and its link's ω and α: G placed in
        the frame A→B by local coordinates, or by a distance and an angle from A→B; a block's
        is its point, and it turns with its guide."""
        if entry.get("block"):
            point = entry["joints"][0]
            _, v, a = self.point(point)
            if point in self.guides:
                return (v, a, *self.spin(*self.guides[point]))
            return v, a, np.zeros(self.n), np.zeros(self.n)
        spec = entry["centre"]
        if "local" in spec:
            u, v = (number(c) * self.unit for c in spec["local"])
        else:
            d = number(spec["distance"]) * self.unit
            turn = math.radians(number(spec.get("angle", 0.0)))
            u, v = d * math.cos(turn), d * math.sin(turn)
        _, vel, acc, w, al = self.carried(*spec["frame"], u, v)
        return vel, acc, w, al


# Excel's functions a load may use, as numpy's (Python's eval reads the load's text)
EXCEL = {"SIGN": np.sign, "IF": np.where, "AND": np.logical_and, "OR": np.logical_or,
         "NOT": np.logical_not, "ABS": np.abs, "SQRT": np.sqrt, "PI": lambda: math.pi}


def power_terms(t: templates.Template, params: dict, motion: Motion, effort,
                book: dict | None = None) -> list:
    """The terms of T12·ω12 (or F_in·v_in) + Σ F·v_P + Σ T·ω + Σ m g·v_G − Σ (m a_G·v_G + I α ω),
    which sum to zero on every row: the links are rigid, the pins and guides frictionless, so
    the power of every effort goes into the kinetic energy (a damper's or a friction's power
    is a load's). `effort`: the book's T12 or F_in; `book`: the book's own Motion columns on
    those rows, which a load that reads the motion reads (book_rates). Each term comes with
    its scale, the product of its factors' magnitudes (|F|·|v|, not |F·v|): a dot product's
    rounding is ε of that, even where the product itself vanishes (a force across its path)."""
    d = t.mechanism.description

    def number(raw):
        """A value of the description: a number, a parameter or arithmetic of parameters and
        the book's rates, per row."""
        if not isinstance(raw, str):
            return float(raw)
        return np.asarray(eval(raw.replace("^", "**"), {"__builtins__": {}},
                               {**EXCEL, **params, **(book or {})}), dtype=float)

    speed = params["omega_in"] if t.mechanism.input_is_angle else \
        params["v_in"] * METRES[t.length_unit]
    terms = [(effort * speed, np.abs(effort * speed))]
    gravity = d.get("dynamics", {}).get("gravity")
    g = (0.0, 0.0)
    if gravity:
        size, angle = number(gravity["g"]), math.radians(number(gravity.get("angle", -90.0)))
        g = (size * math.cos(angle), size * math.sin(angle))
    for load in d.get("loads", []):
        if "torque" in load:
            torque = number(load["torque"]) * motion.spin(*load["body"])[0]
            terms.append((torque, np.abs(torque)))
        else:
            fx, fy = (number(c) for c in load["force"])
            _, (vx, vy), _ = motion.point(load["at"])
            terms.append((fx * vx + fy * vy, np.hypot(fx, fy) * np.hypot(vx, vy)))
    for entry in d.get("bodies", []):
        m, inertia = number(entry["mass"]), number(entry.get("inertia", 0.0))
        (vx, vy), (ax, ay), w, al = motion.centre(entry, number)
        speed_g = np.hypot(vx, vy)
        terms += [(m * (g[0] * vx + g[1] * vy), np.abs(m) * math.hypot(*g) * speed_g),
                  (-m * (ax * vx + ay * vy), np.abs(m) * np.hypot(ax, ay) * speed_g),
                  (-inertia * al * w, np.abs(inertia * al * w))]
    return terms


def assert_power_balance(t: templates.Template, built, values) -> int:
    """The power balance on every row of the Forces sheet (the current position and the
    sweep) where the book has a driving effort, to 1e-9 of the sum of the terms' sizes; the
    number of rows it held on. The velocities come from the kinematic reference, the effort
    from the book."""
    table = built.meta["forces"]
    first, last = table["rows"]
    rows = [table["current_row"], *range(first, last + 1)]
    effort_key = "T12" if t.mechanism.input_is_angle else "F_in"
    effort_col = table["columns"][effort_key]
    efforts = [values[(SHEET, f"{effort_col}{r}")] for r in rows]
    solved = [not engine.is_error(e) for e in efforts]
    rows = [r for r, ok in zip(rows, solved) if ok]
    if not rows:
        return 0
    inputs = [values[(SHEET, f"A{r}")] for r in rows]
    params = t.values()
    motion = Motion(t, params, inputs)
    terms = power_terms(t, params, motion,
                        np.array([e for e, ok in zip(efforts, solved) if ok], dtype=float),
                        {**book_rates(built, values, rows), t.mechanism.input_key:
                         np.radians(inputs) if t.mechanism.input_is_angle else np.asarray(inputs)})
    residual = sum(term for term, _ in terms)
    size = sum(scale for _, scale in terms)
    # a row at a dead centre has no velocities in the kinematic reference (its power cannot be
    # taken), where the book may show any number (verify's rule for an undetermined row)
    rated = np.isfinite(size)
    rows, residual, size = [r for r, ok in zip(rows, rated) if ok], residual[rated], size[rated]
    if not rows:
        return 0
    # 1e-9 of the row's terms' scales; and where every term is near zero (a link's ω passing
    # through 0: its rounding, ~1e-16 of the sweep's powers, is all that is left), 1e-12 of the
    # largest row's
    bound = 1e-9 * size + 1e-12 * size.max()
    worst = np.argmax(np.abs(residual) - bound)
    assert np.all(np.abs(residual) <= bound), (rows[worst], residual[worst], size[worst])
    return len(rows)


def book_rates(built, values, rows) -> dict:
    """The book's own Motion columns on these rows (the Forces sheet's rows are the Motion
    sheet's): what a load that reads the motion reads in the book."""
    motion = built.meta["motion"]
    cell = (lambda v: v if isinstance(v, float) else math.nan)     # #N/A: NaN
    return {key: np.array([cell(values[(motion["sheet"], f"{letter}{r}")]) for r in rows])
            for key, letter in motion["columns"].items()}


def coarse(t: templates.Template, values: dict) -> templates.Template:
    """The drawn values, on a coarse sweep (every 30°, or a dozen actuator lengths)."""
    t = with_values(t, **values)
    step = 30.0 if t.mechanism.input_is_angle else (t.sweep.stop - t.sweep.start) / 12
    return dataclasses.replace(t, sweep=dataclasses.replace(t.sweep, step=step))


def test_the_templates_verify_and_balance_as_written():
    for family in FAMILIES:
        t = load(family)
        built, values = builder.make(t)
        assert_verified(built, values)
        assert assert_power_balance(t, built, values) > 0, family


@pytest.mark.parametrize("family", FAMILIES)
def test_random_masses_and_loads_match_the_reference_and_balance_power(family):
    """For random dimensions, masses, inertias, centres, loads, gravity and input rates: every
    formula cell of the book agrees with the references (verify), and the book's driving
    effort balances the power of the loads, the weights and the inertia on every row."""
    base = load(family)

    balanced = []

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow])
    @given(dynamics(base))
    def check(values):
        t = coarse(base, values)
        built, computed = builder.make(t)
        assert_verified(built, computed)
        balanced.append(assert_power_balance(t, built, computed))

    if family in FOUND:
        check = example(FOUND[family])(check)
    check()
    assert sum(balanced) > EXAMPLES, balanced    # rows with forces, not only unassembled books


@pytest.mark.parametrize("name", ["oscillating-cylinder", "fourbar-slide", "along-ground"])
def test_sliding_pairs_in_other_arrangements(name):
    """Three arrangements an independent review found the writer got wrong or could not build:
    a slide's block pivoted on the ground (its pin to the ground is part of the shaking force),
    a slide's block on a dyad's joint (two groups' determinants at one point), a slider along
    two ground points (a fixed line): each builds, agrees with the reference everywhere and
    balances power on every row."""
    t = load(name)
    built, values = builder.make(t)
    assert_verified(built, values)
    assert assert_power_balance(t, built, values) > 0


# --------------------------------------------------------------------------------------------
# 4. Two cases by hand
# --------------------------------------------------------------------------------------------

def weightless(t: templates.Template, **values) -> templates.Template:
    """Every mass, inertia, load and the gravity zero, but the given values."""
    zero = {p.symbol: 0.0 for p in t.parameters
            if p.kind in ("mass", "inertia", "force", "torque", "acceleration")}
    return with_values(t, **{**zero, **values})


def test_static_fourbar_with_an_output_torque_by_virtual_work():
    """No masses, no gravity, only a torque T on the rocker B0-B (link 4). The links are rigid
    and the pins frictionless, so the powers of the efforts sum to zero (virtual work):
    T12·ω12 + T·ω14 = 0, hence T12 = −T·ω14/ω12, with ω14 from the kinematic reference."""
    torque, w12 = 7.5, 3.0
    t = weightless(load("fourbar"), T4=torque, omega_in=w12, alpha_in=4.0)
    built, values = builder.make(t)
    table = built.meta["forces"]
    first, last = table["rows"]
    rows = [table["current_row"], *range(first, last + 1)]
    inputs = [values[(SHEET, f"A{r}")] for r in rows]
    got = np.array([values[(SHEET, f"{table['columns']['T12']}{r}")] for r in rows])
    w14 = solve(t.mechanism.description, t.values(), np.asarray(inputs))["omega_theta14"]
    np.testing.assert_allclose(got, -torque * w14 / w12, rtol=1e-10)


def efforts(t: templates.Template, key: str = "T12") -> tuple[np.ndarray, np.ndarray]:
    """The inputs (degrees) and a force column of the book built from t, at the current
    position and on every sweep row."""
    built, values = builder.make(t)
    table = built.meta["forces"]
    first, last = table["rows"]
    rows = [table["current_row"], *range(first, last + 1)]
    inputs = np.array([values[(SHEET, f"A{r}")] for r in rows], dtype=float)
    got = np.array([values[(SHEET, f"{table['columns'][key]}{r}")] for r in rows], dtype=float)
    return inputs, got


def test_static_inverted_slider_crank_with_an_output_torque_by_virtual_work():
    """The slide (RPR): no masses, no gravity, only a torque T on link 4 (B0-B), which the block
    at the crank pin A drives along its slide line. The pins and the slide are frictionless and
    the links rigid, so the efforts' powers sum to zero: T12·ω12 + T·ω14 = 0, T12 = −T·ω14/ω12,
    ω14 the rate of link 4's angle θ14 from the kinematic reference."""
    torque, w12 = -4.0, 2.5
    t = weightless(load("inverted-slider-crank"), T4=torque, omega_in=w12, alpha_in=-3.0)
    inputs, got = efforts(t)
    w14 = solve(t.mechanism.description, t.values(), inputs)["omega_theta14"]
    np.testing.assert_allclose(got, -torque * w14 / w12, rtol=1e-10)


def test_static_pump_with_a_plunger_force_by_virtual_work():
    """The slot: no masses, no gravity, only a force F along the plunger's line (x) on its block
    at P, whose pin runs in the rocker's slot. Virtual work: T12·ω12 + F·vPx = 0, with vPx the
    plunger's velocity from the kinematic reference (its line is horizontal), so T12 =
    −F·vPx/ω12; and the plunger's own balance along its line: the slot's push on it, F45x
    (the rocker is link 4, the plunger block 5), is −F."""
    force, w12 = 250.0, 4.0
    t = weightless(load("pump"), FPx=force, omega_in=w12, alpha_in=0.0)
    inputs, got = efforts(t)
    vx = solve(t.mechanism.description, t.values(), inputs)["vx_P"] * 1e-3
    np.testing.assert_allclose(got, -force * vx / w12, rtol=1e-10, atol=1e-12 * force)
    _, push = efforts(t, "F45x")
    np.testing.assert_allclose(push, -force, rtol=1e-12)


def test_inline_slider_crank_piston_inertia_by_hand():
    """In-line slider-crank, crank r = 50 mm, rod l = 200 mm, at a constant ω; only the piston
    has mass m, no gravity, no load. The piston's position x_B = r cos θ + D with
    D = √(l² − r² sin² θ):
        x′  = −r sin θ − r² sin θ cos θ / D
        x″  = −r cos θ − r² cos 2θ / D − r⁴ sin² θ cos² θ / D³
    and v_B = ω·x′, a_B = ω²·x″ (α = 0). The crank and rod are massless and the pins and the
    guide frictionless (the guide's force is normal to the motion), so the motor's power feeds
    only the piston's kinetic energy: T12·ω = d(½ m v_B²)/dt = m·a_B·v_B, T12 = m·a_B·v_B/ω.
    The piston's x equation has the rod's push alone: F34x = m·a_B."""
    r, l, w, m = 50.0, 200.0, 30.0, 2.0
    t = weightless(load("slider-crank"), a1=0.0, a2=r, a3=l, m4=m, omega_in=w, alpha_in=0.0)
    built, values = builder.make(t)
    table = built.meta["forces"]
    first, last = table["rows"]
    rows = [table["current_row"], *range(first, last + 1)]
    th = np.radians([values[(SHEET, f"A{r_}")] for r_ in rows])
    got = {key: np.array([values[(SHEET, f"{table['columns'][key]}{r_}")] for r_ in rows])
           for key in ("T12", "F34x")}
    rm, lm = r * 1e-3, l * 1e-3
    v, a, d = inline_piston(rm, lm, w, th)
    scale = m * np.max(np.abs(a)) * np.max(np.abs(v)) / w
    np.testing.assert_allclose(got["T12"], m * a * v / w, rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(got["F34x"], m * a, rtol=0, atol=1e-10 * m * np.max(np.abs(a)))


def test_a_book_without_a_force_column_the_mechanism_has_cannot_be_verified(tmp_path, capsys):
    """A force the book leaves out is not a force it got right: a record whose Forces sheet
    lacks a column of the reference's (here F23, the size of the crank's pin force) is refused
    with one line naming it, exit 2 — never "all agree"."""
    import openpyxl
    from linkbook.apps import cli
    from linkbook.base import sheets as layout
    path = tmp_path / "slider-crank.xlsx"
    builder.build_file(load("slider-crank"), path)
    wb = openpyxl.load_workbook(path)
    meta = layout.read_meta(wb)
    del meta["forces"]["columns"]["F23"]
    del wb[layout.META]
    layout.write_meta(wb.create_sheet(layout.META), meta)
    wb.save(path)
    capsys.readouterr()
    assert cli.main(["verify", str(path)]) == 2
    out = capsys.readouterr()
    assert "no column of F23" in out.out + out.err


def test_an_inertia_force_beyond_the_loads_scale_carries_its_accelerations_allowance():
    """The pump's plunger alone with mass (0.5 kg), the crank starting from rest at 5 rad/s²,
    dimensions hypothesis found: on one row the slot is within rounding of parallel to the
    plunger's line, its acceleration some 3e11 m/s², and the pins carry 1.9e11 N where the
    masses' and the loads' own scale F₀ is 7 N. The kinematics allows that acceleration its
    growth (1e-12·a²/m); the forces on that row the same, 1e-12·X²/F₀ (the book's are within
    1e-11 of the reference's; the bound of 1e-12·F alone refused them)."""
    values = {"a2": 27.5, "a3": 48.0, "a4": 273.28125, "b1": 260.15625, "c4": 105.0, "s1": 20.0,
              "branch": -1.0, "m2": 0.0, "I2": 0.0, "m3": 0.0, "I3": 0.0, "m4": 0.0, "I4": 0.0,
              "u4": 57.93, "v4": -10.42, "m5": 0.5, "g": 0.0, "Fp": 0.0, "delivery_from": 0.0,
              "delivery_to": 0.0, "omega_in": 0.0, "alpha_in": 5.0}
    built, computed = builder.make(dimensioned(templates.load("pump"), values))
    checks = checks_of(built, computed)
    assert not [m for c in checks for m in c.mismatches[:2]]
    forces = next(c for c in checks if c.block == "Forces" and c.name == "F12")
    assert forces.max_abs > 1.0 and forces.cells > 0       # the row is there, and far out
