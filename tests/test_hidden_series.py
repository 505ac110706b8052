"""A chart series that lies exactly on another (a rigid link's ω is its other angle's ω) says so
in its legend entry, where the independent reference finds the two equal over the whole sweep."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import built, template

from linkbook.check import reference as generic
from linkbook.book.charts import same_curve


def _motion_legends(name: str) -> dict[str, str]:
    """{symbol: legend entry} of every series of the Charts sheet's angular charts."""
    b, _ = built(name)
    entries = {}
    for chart in b.workbook["Charts"]._charts:
        for s in chart.series:
            text = s.tx.v if s.tx is not None and s.tx.v else ""
            if text.startswith(("ω", "α")):
                entries[text.split(" (")[0]] = text
    return entries


def _equal_pairs(name: str) -> set[frozenset]:
    """Pairs of the book's angular velocity and acceleration columns that the reference finds
    equal at every row (NaN at the same rows), each pair as the two symbols."""
    b, _ = built(name)
    t = template(name)
    ref = generic.solve(t.mechanism.description, t.values(), np.array(t.sweep.angles()))
    symbols = {q.key: q.symbol for q in b.model.quantities}
    keys = [k for k in b.meta["motion"]["columns"] if k.startswith(("omega_", "alpha_"))]
    pairs = set()
    for i, a in enumerate(keys):
        for c in keys[i + 1:]:
            x, y = ref[a], ref[c]
            if a[:5] == c[:5] and np.allclose(x, y, rtol=0, equal_nan=True,
                                              atol=1e-9 * np.nanmax(np.abs(x))):
                pairs.add(frozenset((symbols[a], symbols[c])))
    return pairs


@pytest.mark.parametrize("name", ["slider-crank", "watt-sixbar", "fourbar"])
def test_the_legend_names_the_series_it_coincides_with(name):
    legends = _motion_legends(name)
    pairs = _equal_pairs(name)
    assert bool(pairs) == (name != "fourbar")      # the four-bar's links all turn differently
    for symbol, text in legends.items():
        partners = sorted(o for p in pairs if symbol in p for o in p if o != symbol)
        expected = f"{symbol} (= {', '.join(partners)}: one curve)" if partners else symbol
        assert text == expected


def test_equal_means_equal_everywhere_and_undefined_at_the_same_rows():
    a = np.array([1.0, 2.0, np.nan, -3.0])
    assert same_curve(a, a.copy())
    assert same_curve(a, a * (1 + 1e-13))
    assert not same_curve(a, np.array([1.0, 2.0, np.nan, -3.001]))
    assert not same_curve(a, np.array([1.0, 2.0, 0.0, -3.0]))       # defined where a is not
    assert not same_curve(np.full(3, np.nan), np.full(3, np.nan))   # nothing drawn at all
