"""The triad's book (docs/coupled-loops.md): Newton–Raphson in the sweep's columns, row to row,
judged cell by cell against the reference (its own six-distance Newton, and at each iteration
its own residuals, Jacobian and correction at the book's iterate).

Random triads driven by a crank that close all round, each built from a random assembly at
θ = 0 and sketched near it; the example template (tests/data/triad-sixbar.toml) in its other
assembly; a linkage that closes on three stretches of the turn, #N/A exactly between them;
LibreOffice's recalculation of the example.
"""
from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from conftest import ROOT, checks_of, examples
from test_triad_reference import conditioning
from linkbook.base.errors import InputError
from linkbook.book import builder
from linkbook.check.reference import solve
from linkbook.language import templates

TEMPLATE = ROOT / "tests" / "data" / "triad-sixbar.toml"
POINT = st.tuples(st.floats(-60, 60), st.floats(-60, 60))
JOINTS = ("xD", "yD", "xE", "yE", "xF", "yF")


def _data(iterations: int = 4, **values) -> dict:
    """The bundled triad six-bar's template with these parameter values and iterations."""
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


def _assembly(crank, b0, c0, joints, sketch) -> dict:
    """Parameters of the bundled template for the triad of this assembly at θ = 0."""
    ends = [(crank, 0.0), b0, c0]
    lengths = [math.dist(p, j) for p, j in zip(ends, joints)]
    sides = [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
    return dict(a2=crank, xB=b0[0], yB=b0[1], xC=c0[0], yC=c0[1], a3=lengths[0],
                a4=lengths[1], a5=lengths[2], d=sides[0], e=sides[1], f=sides[2],
                sxD=sketch[0][0], syD=sketch[0][1], sxE=sketch[1][0], syE=sketch[1][1],
                sxF=sketch[2][0], syF=sketch[2][1])


STEP = 15.0


@settings(max_examples=examples(8), suppress_health_check=[HealthCheck.filter_too_much])
@given(crank=st.floats(2, 8), b0=POINT, c0=POINT, d=POINT, e=POINT, f=POINT,
       off=st.lists(st.floats(-1, 1), min_size=6, max_size=6))
def test_random_triads_agree_with_the_reference_cell_by_cell(crank, b0, c0, d, e, f, off):
    """Every cell of the book (vector engine) within verify's bounds of the reference.
    Triads that close on every row, each 2 % or more away from a dead centre: nearer one, or
    restarting from the sketch after a gap, the book's Newton (in two angles) and the
    reference's (in six coordinates) may each reach another assembly, which verify names as
    a difference; this test does not draw that (test_..._na_exactly_between has gaps)."""
    joints, ends = [d, e, f], [(crank, 0.0), b0, c0]
    shortest = min([math.dist(p, j) for p, j in zip(ends, joints)]
                   + [math.dist(joints[k], joints[(k + 1) % 3]) for k in range(3)]
                   + [math.dist(ends[k], ends[(k + 1) % 3]) for k in range(3)])
    assume(shortest >= 6)
    sketch = [(j[0] + 0.01 * shortest * off[2 * k], j[1] + 0.01 * shortest * off[2 * k + 1])
              for k, j in enumerate(joints)]
    data = _data(8, **_assembly(crank, b0, c0, joints, sketch))
    params = {k: v["value"] for k, v in data["parameters"].items()}
    angles = np.arange(0.0, 360.0 + STEP / 2, STEP)
    ref = solve(data["mechanism"], params, angles)
    assume(np.isfinite(ref["xD"]).all())
    assume(all(conditioning([(crank * math.cos(t), crank * math.sin(t)), b0, c0],
                             [(ref[f"x{n}"][i], ref[f"y{n}"][i]) for n in "DEF"]) > 0.02
               for i, t in enumerate(np.radians(angles)) if np.isfinite(ref["xD"][i])))
    b, values = _book(data, step=STEP)
    assert not _mismatches(b, values)


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
    params = _assembly(20.0, (80.0, 0.0), (10.0, 70.0), joints, joints)
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
    data = _data(8, **_assembly(20.0, (80.0, 0.0), (10.0, 70.0), joints, joints))
    data["sweep"]["step"] = 5
    path = tmp_path / "stretches.xlsx"
    builder.build_file(templates.from_data("triad", data), path)
    assert main(["verify", str(path)]) == 2
    said = capsys.readouterr().out.splitlines()
    verdict = [line for line in said if line.startswith("CANNOT JUDGE")]
    assert len(verdict) == 1 and "DIFFER" not in "".join(said), said
    assert "Sweep rows 69–77: the book's assembly of the triad D differs from the reference's " \
           "after a restart at row 69" in verdict[0], verdict


def test_masses_on_a_triad_are_refused_in_one_line():
    data = _data()
    data["mechanism"]["bodies"] = [{"joints": ["D", "E", "F"], "mass": 1.0,
                                    "centre": {"frame": ["D", "E"], "distance": 10.0}}]
    with pytest.raises(InputError) as caught:
        _book(data)
    message = str(caught.value)
    assert "\n" not in message and "(triad D E F)" in message and "force analysis" in message


def test_a_triad_in_a_grid_is_refused_in_one_line():
    data = _data()
    data["grid"] = {"parameter": "a2", "output": "yF", "values": [10.0, 12.0]}
    with pytest.raises(InputError) as caught:
        _book(data)
    message = str(caught.value)
    assert "\n" not in message and "grid" in message and "(triad D E F)" in message


@pytest.mark.libreoffice
def test_libreoffice_recalculates_the_example_book_like_the_reference(needs, tmp_path):
    """The iterations are ordinary cells: LibreOffice's full recalculation of the example book
    (no iterative-calculation setting) agrees with the reference in every formula cell."""
    needs("libreoffice")
    import linkbook
    path = linkbook.build(TEMPLATE, tmp_path / "triad-sixbar.xlsx")
    report = linkbook.verify(path, engine="libreoffice")
    assert report.status == 0, [(c.name, c.mismatches[:2]) for c in report.checks if not c.ok]
    assert report.formula_cells > 7000
