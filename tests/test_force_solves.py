"""What verify solves for the forces (issue 42): per input set, the force reference's positions
over the sweep once, taken on both to the forces as given and to the forces with the input at
rest (the force scale, check/force_cells.py), where no value the positions take reads the
input's speed or acceleration; and that sharing changes no value of the reference's."""
from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from linkbook.book import builder
from linkbook.check import verifier
from linkbook.check.forces import forces, forces_and_at_rest
from linkbook.check.reference import analysis, reads_rates
from linkbook.language import templates

RATES = ("omega_in", "alpha_in")
COARSE = np.arange(0.0, 360.0, 30.0)


def _same(a, b) -> bool:
    """Bit for bit: the same keys, each array of the same bytes."""
    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        b = np.asarray(b)
        return a.shape == b.shape and a.dtype == b.dtype and a.tobytes() == b.tobytes()
    return a == b


@pytest.fixture(scope="module")
def fourbar():
    return templates.load("fourbar")


def _solves(monkeypatch, book_steps: int) -> list[tuple[bool, int, tuple, bool]]:
    """Each Positions the reference makes from now on, as (of a description with more steps
    than the book's: the force reference's, its centres of mass added; rows; the parameters but
    the input's speed and acceleration: which input set; with the speed given)."""
    made, real = [], analysis.Positions

    class Counted(real):
        def __init__(self, description, params, angles, *rest):
            super().__init__(description, params, angles, *rest)
            made.append((len(self.steps) > book_steps, self.n,
                         tuple(sorted((k, v) for k, v in params.items()
                                      if k not in RATES and k != "to_metres")),
                         RATES[0] in params))
    monkeypatch.setattr(analysis, "Positions", Counted)
    return made


def test_verify_solves_the_force_positions_once_per_input_set(fourbar, tmp_path, monkeypatch):
    path = tmp_path / "fourbar.xlsx"
    builder.build_file(fourbar, path)
    rows = len(fourbar.sweep.angles())
    made = _solves(monkeypatch, len(fourbar.mechanism.description["steps"]))
    report = verifier.verify(path)
    assert report.status == 0
    judged = {inputs for forced, n, inputs, moving in made if not forced and n == rows and moving}
    over_the_sweep = Counter(inputs for forced, n, inputs, _ in made if forced and n == rows)
    assert len(judged) >= 2                       # the book's inputs and another set
    assert set(over_the_sweep) == judged
    assert set(over_the_sweep.values()) == {1}, over_the_sweep


def _with_load(description: dict, torque: str) -> dict:
    return {**description, "loads": [*description.get("loads", []),
                                     {"body": ["B0", "B"], "torque": torque}]}


def _still(params: dict) -> dict:
    return {**params, **dict.fromkeys(RATES, 0.0)}


@pytest.mark.parametrize("name", ["fourbar", "slider-crank", "pump"])
def test_the_shared_positions_give_the_forces_of_two_solves(name):
    t = templates.load(name)
    d, params = t.mechanism.description, t.values()
    if name == "fourbar":        # a load of the input's speed itself: at rest it reads 0
        d = _with_load(d, "-1e-3*omega_in")
    moving, resting = forces_and_at_rest(d, params, COARSE, t.length_unit)
    assert _same(moving, forces(d, params, COARSE, t.length_unit))
    assert _same(resting, forces(d, _still(params), COARSE, t.length_unit))
    assert not _same(moving, resting)


@pytest.mark.parametrize("spelt", ["omega_in", "OMEGA_IN"])
def test_positions_that_read_the_speed_are_solved_again_at_rest(fourbar, spelt):
    """A ground point placed by the input's speed: the positions at rest are others."""
    d = fourbar.mechanism.description
    d = {**d, "ground": {**d["ground"], "B0": [f"a1 + {spelt}/2", 0]}}
    params = fourbar.values()
    assert reads_rates(d)
    _, resting = forces_and_at_rest(d, params, COARSE, fourbar.length_unit)
    assert _same(resting, forces(d, _still(params), COARSE, fourbar.length_unit))


def test_reads_rates_looks_at_the_positions_values_alone():
    steps = [{"type": "crank", "point": "A", "pivot": "A0", "length": "a2"}]
    bare = {"input": {"key": "theta12"}, "ground": {"A0": [0, 0]}, "steps": steps}
    assert not reads_rates(bare)
    assert not reads_rates({**bare, "loads": [{"at": "A", "force": ["c*omega_in", 0]}]})
    assert not reads_rates({**bare, "ground": {"A0": ["omega_inner", 0]}})
    assert reads_rates({**bare, "steps": [*steps, {"type": "point", "point": "C",
                                                   "frame": ["A0", "A"],
                                                   "local": [1, "v_in * 2"]}]})
    assert reads_rates({**bare, "steps": [*steps, {"type": "expression", "key": "w",
                                                   "formula": "2*Alpha_In"}]})


def test_condition_numbers_kept_for_the_rows_whose_matrix_is_the_same():
    """numpy's own condition numbers, to the bit, whichever rows changed since the last
    system (one entry scaled, a row made singular)."""
    from linkbook.check.forces.equations import Conditions
    first = np.stack([np.eye(3) + 0.1 * k * np.arange(9.0).reshape(3, 3) for k in range(6)])
    second = first.copy()
    second[2, 0, 1] *= 3.0
    second[4] = np.diag([1.0, 1e-9, 0.0])
    conditions = Conditions()
    for A in (first, second, second.copy(), first):
        assert np.linalg.cond(A).tobytes() == conditions(A).tobytes()
