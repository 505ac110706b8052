"""The triad's book (docs/coupled-loops.md): Newton–Raphson in the sweep's columns, row to row,
judged cell by cell against the reference (its own six-distance Newton, and at each iteration
its own residuals, Jacobian and correction at the book's iterate).

A hundred random triads driven by a crank, each from a random assembly at θ = 0 sketched near
it, judged in one book evaluated again at their inputs (as verify's input sets are); the
bundled template (templates/triad-sixbar.toml) in its other assembly; a linkage that closes on
three stretches of the turn, #N/A exactly between them and named where the book reaches
another assembly than the reference. The bundled book itself is judged by the tests of every
bundled template (LibreOffice's and Gnumeric's recalculation among them).
"""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from conftest import ROOT, checks_of, examples
from linkbook.base.errors import InputError
from linkbook.base.sheets import SWEEP
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.language import templates

TEMPLATE = ROOT / "templates" / "triad-sixbar.toml"
JOINTS = ("xD", "yD", "xE", "yE", "xF", "yF")


def _data(iterations: int = 4, **values) -> dict:
    """The bundled triad six-bar's template with these parameter values and iterations, no
    charts."""
    data = tomllib.loads(TEMPLATE.read_text(encoding="utf-8"))
    data["mechanism"]["steps"][1]["iterations"] = iterations
    for symbol, value in values.items():
        data["parameters"][symbol]["value"] = float(value)
    data["mechanism"].pop("charts")
    return data


def _book(data: dict, step: float | None = None):
    if step is not None:
        data["sweep"]["step"] = step
    return builder.make(templates.from_data("triad", data))


def _column(b, values, key: str) -> np.ndarray:
    ws = b.workbook["Sweep"]
    first, last = b.meta["sweep"]["rows"]
    letter = b.meta["sweep"]["columns"][key]
    got = [values[("Sweep", f"{letter}{r}")] for r in range(first, last + 1)]
    assert all(isinstance(ws[f"{letter}{r}"].value, str) for r in range(first, last + 1))
    return np.array([v if isinstance(v, float) else math.nan for v in got])


def _mismatches(b, values) -> list:
    return [(c.block, c.name, m) for c in checks_of(b, values) for m in c.mismatches[:2]]


def triad_assembly(crank, b0, c0, joints, sketch) -> dict:
    """Parameters of the bundled template for the triad of this assembly at θ = 0."""
    ends = [(crank, 0.0), b0, c0]
    lengths = [math.dist(p, j) for p, j in zip(ends, joints)]
    sides = [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
    return dict(a2=crank, xB=b0[0], yB=b0[1], xC=c0[0], yC=c0[1], a3=lengths[0],
                a4=lengths[1], a5=lengths[2], d=sides[0], e=sides[1], f=sides[2],
                sxD=sketch[0][0], syD=sketch[0][1], sxE=sketch[1][0], syE=sketch[1][1],
                sxF=sketch[2][0], syF=sketch[2][1])


RANDOM_TRIADS = examples(100, at_least=5)
RANDOM_STEP = 30.0      # degrees: 13 rows a turn, each row 30° on from the row above
RANDOM_ITERATIONS = 6   # the language's default


@pytest.fixture(scope="module")
def one_book():
    """The template's book at RANDOM_STEP and RANDOM_ITERATIONS, built once, and the vector
    engine that evaluated it (verify's input sets evaluate a book again at other inputs so)."""
    from linkbook.engine import evaluator as engines
    b, _ = _book(_data(RANDOM_ITERATIONS), step=RANDOM_STEP)
    evaluation = engines.Engine(b.workbook)
    evaluation.run_view()
    return b, evaluation


def _random_triad(rng) -> tuple[dict, float]:
    """A crank and a triad drawn at random from an assembly at θ = 0 (in a 120 mm box, no
    distance below 6 mm) sketched up to 2 % of its shortest distance off it: the template's
    parameters, and the ternary's turning sense (+1 counter-clockwise)."""
    while True:
        crank = rng.uniform(2.0, 25.0)
        b0, c0, d, e, f = (tuple(rng.uniform(-60.0, 60.0, 2)) for _ in range(5))
        joints, ends = [d, e, f], [(crank, 0.0), b0, c0]
        shortest = min([math.dist(p, j) for p, j in zip(ends, joints)]
                       + [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
                       + [math.dist(ends[k], ends[(k + 1) % 3]) for k in range(3)])
        if shortest >= 6.0:
            break
    off = rng.uniform(-1.0, 1.0, 6)
    sketch = [(j[0] + 0.02 * shortest * off[2 * k], j[1] + 0.02 * shortest * off[2 * k + 1])
              for k, j in enumerate(joints)]
    sense = np.sign((e[0] - d[0]) * (f[1] - d[1]) - (e[1] - d[1]) * (f[0] - d[0]))
    return triad_assembly(crank, b0, c0, joints, sketch), float(sense)


def test_a_hundred_random_triads_agree_with_the_reference_cell_by_cell(one_book):
    """RANDOM_TRIADS random triads, each judged in every formula cell verify judges at an input
    set (the sweep, the current position and its joints, the constants, Motion) against the
    reference, in one book evaluated again at each triad's inputs. Both turning senses of
    the ternary; some close all round, some lose their assembly part way (#N/A exactly where
    the reference finds none) and restart from the sketch after the gap, where the book may
    reach another assembly than the reference: verify names those rows, and that named
    verdict is the only one accepted besides agreement."""
    from linkbook.check.checks import Rules
    from linkbook.check.input_sets import input_cell, write_inputs
    from linkbook.check.judge import judge_book
    from linkbook.engine import evaluator as engines
    from linkbook.engine.rerun import rerun
    b, evaluation = one_book
    rules = Rules(engines.is_error, engines.error_code)
    rng = np.random.default_rng(41)
    seen = {"counter-clockwise": 0, "clockwise": 0, "all round": 0, "losing": 0, "named": 0}
    for _ in range(RANDOM_TRIADS):
        params, sense = _random_triad(rng)
        held = write_inputs(b.workbook, b.record, params)
        try:
            with rerun(evaluation, {input_cell(b.record, k): v
                                    for k, v in params.items()}) as values:
                checks = judge_book(b.workbook, b.record, values, rules, own_inputs=False)
        finally:
            write_inputs(b.workbook, b.record, held)
        bad = [(c.block, c.name, m) for c in checks for m in c.mismatches[:2]]
        assert not bad, (params, bad[:4])
        theta = next(c for c in checks if c.block == SWEEP and c.name == "theta_D")
        seen["counter-clockwise" if sense > 0 else "clockwise"] += 1
        seen["losing" if theta.na_expected else "all round"] += 1
        seen["named"] += any(c.assembly for c in checks)
    if RANDOM_TRIADS >= 50:                 # the mix the issue asks for, at the default count
        assert min(seen.values()) >= 5, seen


def test_the_example_in_its_other_assembly():
    """The example linkage sketched in another of its assemblies: the book's Newton finds that
    one (its joints differ from the bundled assembly's) and every cell agrees."""
    base = _data()
    b1, v1 = _book(base, step=10)
    other = _data(sxD=66.6, syD=49.2, sxE=20.0, syE=11.4, sxF=42.5, syF=67.0)
    b2, v2 = _book(other, step=10)
    assert not _mismatches(b2, v2)
    first, second = _column(b1, v1, "xD"), _column(b2, v2, "xD")
    assert np.isfinite(second).any()
    assert np.nanmax(np.abs(first - second)) > 10.0


def test_a_triad_that_closes_on_stretches_of_the_turn_is_na_exactly_between():
    """A crank of 20 mm that the triad follows only near θ = 0, 70°-100° and 320°-360°: the
    book's solution is #N/A on exactly the rows where the reference finds none. Each stretch
    after a gap starts from the sketch again, in the book by Newton in its two angles, in the
    reference in the six coordinates: from the sketch at 70° both reach one assembly; from the
    sketch at 320° they reach two different ones, and verify names that stretch, and only
    that one, as such (not passed), where every cell agrees with the book's assembly."""
    joints = [(35.0, 25.0), (60.0, 30.0), (45.0, 45.0)]
    params = triad_assembly(20.0, (80.0, 0.0), (10.0, 70.0), joints, joints)
    b, values = _book(_data(8, **params), step=5)
    angles = np.arange(0.0, 360.1, 5.0)
    ref = solve(_data(8, **params)["mechanism"], params, angles)
    closes = np.isfinite(ref["xD"])
    assert np.count_nonzero(np.diff(closes.astype(int)) == 1) == 2    # two restarts
    for key in JOINTS:
        np.testing.assert_array_equal(np.isfinite(_column(b, values, key)), closes)
    assert not _mismatches(b, values)
    first = b.meta["sweep"]["rows"][0]
    second = int(np.nonzero(np.diff(closes.astype(int)) == 1)[0][1]) + 1    # 320°
    last = len(angles) - 1
    named = [line for c in checks_of(b, values) for line in c.assembly]
    assert named == [f"Sweep rows {first + second}–{first + last}: the book's assembly of the "
                     f"triad D differs from the reference's after a restart at row "
                     f"{first + second}"], named


def test_verify_names_the_stretch_in_another_assembly_in_one_line(tmp_path, capsys):
    """`linkbook verify` of the book above: exit status 2 (not passed, nothing differs), and
    the stretch named in one line of the verdict."""
    from linkbook.apps.cli import main
    joints = [(35.0, 25.0), (60.0, 30.0), (45.0, 45.0)]
    data = _data(8, **triad_assembly(20.0, (80.0, 0.0), (10.0, 70.0), joints, joints))
    data["sweep"]["step"] = 5
    path = tmp_path / "stretches.xlsx"
    builder.build_file(templates.from_data("triad", data), path)
    assert main(["verify", str(path)]) == 2
    said = capsys.readouterr().out.splitlines()
    verdict = [line for line in said if line.startswith("CANNOT JUDGE")]
    assert len(verdict) == 1 and "DIFFER" not in "".join(said), said
    assert "Sweep rows 69–77: the book's assembly of the triad D differs from the reference's " \
           "after a restart at row 69" in verdict[0], verdict


def test_a_triad_in_a_grid_is_refused_in_one_line():
    data = _data()
    data["grid"] = {"parameter": "a2", "output": "yF", "values": [10.0, 12.0]}
    with pytest.raises(InputError) as caught:
        _book(data)
    message = str(caught.value)
    assert "\n" not in message and "grid" in message and "(triad D E F)" in message
