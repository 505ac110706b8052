"""Every template, on its defaults and on other dimension sets, against the independent reference:
every formula cell within 1e-9 (mm or deg; rad for radian columns) or #N/A exactly where the
reference finds that the loop cannot close."""
from __future__ import annotations

from functools import lru_cache

import pytest

from conftest import ROOT, built, checks_of, formula_cells
from linkbook.engine import evaluator as engine
from linkbook.language import templates

CASES = [
    # (template, --set, --branch)
    ("fourbar", (), None),
    ("fourbar", ("a2=40", "b3=90"), "crossed"),
    ("fourbar", ("a1=100", "a2=60", "a3=50", "a4=40"), None),   # non-Grashof: no full turn
    ("fourbar", ("a1=60", "a2=25", "a3=70", "a4=45", "b3=50", "c3=40"), "crossed"),
    ("slider-crank", (), None),
    ("slider-crank", ("a1=-10", "a3=180", "gamma3=-40"), "crossed"),
    ("slider-crank", ("a1=40", "a3=60"), None),                 # cannot close below the line
    ("pump", (), None),
    ("pump", ("s1=0,35,120", "a4=150"), "crossed"),
    ("pump", ("s1=90,260,330", "a3=180"), None),                # large s1: gaps in the cycle
    ("inverted-slider-crank", (), None),
    ("inverted-slider-crank", ("a1=60", "a2=80", "a4=45"), "crossed"),  # p < a4 near θ12 = 0
    ("inverted-slider-crank", ("a4=0",), None),                 # in-line
    ("quick-return", (), None),
    ("quick-return", ("a2=80", "a5=200", "b1=380"), "crossed"),
    ("quick-return", ("a5=30",), None),                         # ram link too short at times
    ("shaper", (), None),
    ("shaper", ("r1=80", "r2=30", "r6=20"), None),
    ("shaper", ("r2=55", "r6=10"), None),
    ("garage-door", (), None),
    ("garage-door", ("a2=35", "b2=100", "a6=170"), "crossed"),
    ("garage-door", ("a5=60", "a6=70"), None),                  # door dyad cannot always close
    ("tk-fourbar", (), None),
    ("tk-fourbar", (), "crossed"),
    ("tk-fourbar", ("a=0.8", "c=1.2"), None),                   # non-Grashof variant
]


@lru_cache(maxsize=None)
def checked(name: str, sets: tuple, branch):
    """(Built, verify's checks) of a case, judged once for both tests of it (read only)."""
    b, values = built(name, sets, None, branch)
    return b, checks_of(b, values)


@pytest.mark.parametrize("name,sets,branch", CASES,
                         ids=[f"{n}-{'-'.join(s) or 'default'}-{b or 'tpl'}" for n, s, b in CASES])
def test_every_formula_cell_matches_the_reference(name, sets, branch):
    b, checks = checked(name, sets, branch)
    bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:3]]
    assert not bad, bad[:10]
    # Every formula cell of the workbook was compared: no column is left unchecked.
    assert sum(c.cells for c in checks) == len(formula_cells(b.workbook))
    # 1e-9 mm or rad; a velocity's in per second of the input's speed scale (|ω|), an
    # acceleration's per second² (ω² + |α|); a time ratio is measured on the reference's
    # motion (its reversals located to 1e-6°), and judged relative to 1e-6; a force (a moment)
    # to 1e-12 of the mechanism's force scale F (F·S), as a length to 1e-9 mm is to 1e-12 of a
    # metre-sized mechanism (the crank shaper with a short link carries some 4e4 N)
    forces = [c for c in checks if c.block.lower().startswith("forces") and c.scale
              and not c.name.startswith(("xG", "yG", "axG", "ayG"))]   # not the centres
    assert max(c.max_abs / c.rate for c in checks if not c.block.startswith("reversals")
               and c not in forces) <= 1e-9
    assert all(c.max_abs <= 1e-12 * c.scale for c in forces), \
        max((c.max_abs / c.scale, c.block, c.name) for c in forces)


@pytest.mark.parametrize("name,sets,branch", [
    ("fourbar", ("a1=100", "a2=60", "a3=50", "a4=40"), None),
    ("slider-crank", ("a1=40", "a3=60"), None),
    ("pump", ("s1=90,260,330", "a3=180"), None),
    ("inverted-slider-crank", ("a1=60", "a2=80", "a4=45"), "crossed"),
    ("quick-return", ("a5=30",), None),
    ("garage-door", ("a5=60", "a6=70"), None),
    ("tk-fourbar", ("a=0.8", "c=1.2"), None),
])
def test_cases_that_cannot_close_really_have_na_rows(name, sets, branch):
    """The cases above meant to exercise #N/A do: both assembled and unassembled rows."""
    _, checks = checked(name, sets, branch)
    na = sum(c.na_expected for c in checks)
    assert na > 0 and all(c.na_agree == c.na_expected for c in checks)
    assert sum(c.cells for c in checks) > na


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "templates").glob("*.toml")))
def test_build_values_equal_a_fresh_evaluation_of_the_saved_layout(name):
    """builder.make evaluates once, moves the degree windows and evaluates only the degree views
    again (the rest taken as known): that must be exactly what a whole evaluation of the final
    workbook gives, i.e. no formula reads a degree view."""
    b, values = built(name)
    fresh = engine.evaluate(b.workbook)
    assert set(values) <= set(fresh)        # charts add a sheet of titles after the evaluation
    differ = [k for k in values if not _same(fresh[k], values[k])]
    assert not differ, differ[:5]


def _same(a, b) -> bool:
    if engine.is_error(a) or engine.is_error(b):
        return engine.is_error(a) and engine.is_error(b) and engine.error_code(a) == engine.error_code(b)
    return a == b or (a != a and b != b)


def test_a_step_that_does_not_divide_the_turn_still_closes_it():
    """--step 25 over 0…360°: 0, 25, …, 350 and then 360 (one shorter step), so the last row is
    the first position again and the coupler curve is closed; every cell still verifies."""
    b, values = built("fourbar", (), 25)
    first, last = b.meta["sweep"]["rows"]
    ws = b.workbook["Sweep"]
    assert [ws[f"A{r}"].value for r in (first, last - 1, last)] == [0, 350, 360]
    x, y = b.meta["sweep"]["columns"]["xC"], b.meta["sweep"]["columns"]["yC"]
    for col in (x, y):
        assert values[("Sweep", f"{col}{last}")] == pytest.approx(
            values[("Sweep", f"{col}{first}")], abs=1e-9)
    assert not [m for c in checks_of(b, values) for m in c.mismatches]


@pytest.mark.parametrize("name, legend", [
    ("fourbar", ["link 1: ground", "link 2: A0A", "link 3: ABC", "link 4: BB0"]),
    ("watt-sixbar", ["link 1: ground", "link 2: A0A", "link 3: AB", "link 4: B0BC",
                     "link 5: CD", "link 6: D0D"]),
])
def test_the_drawing_numbers_links_as_the_textbook_does(name, legend):
    """Ground = link 1, drawn through the fixed pivots (grey, triangles), crank = link 2, …"""
    b, values = built(name)
    chart = b.workbook["Mechanism"]._charts[0]
    titles = [s.tx.strRef.f if s.tx.strRef else s.tx.v for s in chart.series]
    assert titles[:len(legend)] == legend
    ground = chart.series[0]
    assert ground.marker.symbol == "triangle"
    record = b.meta["position"]["drawing"][0]
    assert record["ground"] and set(record["joints"]) == set(
        templates.load(name).mechanism.description["ground"]) & set(record["joints"])
    assert len(record["joints"]) >= 2
