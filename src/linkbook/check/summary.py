"""The judge of where the mechanism assembles: the sweep's closes and gap columns, and the
geometry summary (assembles, gaps, the output's and each transmission angle's range, each
four-bar loop's lengths, Grashof class and limit angles) from the reference."""
from __future__ import annotations

import math

import numpy as np

from . import reference as generic
from ..base import sheets as layout
from ..base.sheets import summary_prefix
from ..base.xlsx import column_cells
from ..language.model import RAD
from .checks import EDGE_SLOPE, ROUNDING, Check, compare_exact
from .context import Judging

DASH = layout.DASH


def check_assembly(j: Judging) -> list[Check]:
    """The closes and gap columns of the sweep, then the summary block."""
    sweep, model, solver = j.record.sweep, j.model, j.solver
    cols, (r0, r1) = sweep.columns, sweep.rows
    closes = np.asarray(j.ref["assembled"], dtype=bool)
    starts, ends = _gaps(j.angles, closes)
    checks = []
    for key, expected in (("closes", [1.0 if c else 0.0 for c in closes]),
                          ("gap_from", starts), ("gap_to", ends)):
        c = Check(layout.SWEEP, key, j.size)
        cells = column_cells(cols[key], r0, r1)
        unit = "" if key == "closes" else solver.mechanism.input_unit
        compare_exact(c, sweep.sheet, cells, j.got(sweep.sheet, cells), expected,
                      units=[unit] * len(cells))
        checks.append(c)
    expected = _summary_expected(model, solver, j.params, j.ref, closes, starts, ends,
                                 _shown_output_degrees(model, sweep, j.values))
    slack = _edge_slack(model, j.ref, closes)
    c = Check("summary", "geometry", j.size)
    for key, info in j.record.summary.items():
        if isinstance(expected[key], float) and math.isnan(expected[key]):
            j.compare(c, layout.MECH, [info.cell], np.array([math.nan]), info.unit)  # #N/A
            continue
        compare_exact(c, layout.MECH, [info.cell], j.got(layout.MECH, [info.cell]),
                      [expected[key]], [slack.get(key, 0.0)], [info.unit])
    checks.append(c)
    return checks


def _gaps(angles: np.ndarray, closes: np.ndarray) -> tuple[list, list]:
    """Per row: the angle where a run of rows that cannot close starts / ends, else a dash."""
    n = len(angles)
    starts = [float(angles[i]) if not closes[i] and (i == 0 or closes[i - 1]) else DASH
              for i in range(n)]
    ends = [float(angles[i]) if not closes[i] and (i == n - 1 or closes[i + 1]) else DASH
            for i in range(n)]
    return starts, ends



def _edge_slack(model, ref, closes: np.ndarray) -> dict[str, float]:
    """A sampled extreme taken on a row next to a row that cannot close sits at a limit
    position (a double root): it gets the same √ε-level allowance as that cell itself."""
    edge = closes & ~(np.roll(closes, 1) & np.roll(closes, -1))
    out = {}
    output_scale = 180.0 / math.pi if model.output and model.get(model.output).unit == RAD \
        else 1.0
    extremes = [("output", model.output, output_scale)] + [
        (summary_prefix("mu", i), key, 180.0 / math.pi)
        for i, key in enumerate(model.transmissions, start=1)]
    for prefix, key, scale in extremes:
        if not key:
            continue
        x = np.asarray(ref[key], dtype=float) * scale
        finite = np.isfinite(x)
        if not finite.any():
            continue
        for name, pick in (("min", np.nanargmin), ("max", np.nanargmax)):
            i = int(pick(np.where(finite, x, np.nan)))
            out[f"{prefix}_{name}"] = ROUNDING * EDGE_SLOPE if edge[i] else 0.0
    return out


def _extreme(values: np.ndarray, fn) -> object:
    values = values[np.isfinite(values)]
    return DASH if values.size == 0 else float(fn(values))


def _shown_output_degrees(model, sweep, values: dict) -> list | None:
    """An angle output's degree view as the book shows it, row by row (None for a length)."""
    if not model.output or model.get(model.output).unit != RAD:
        return None
    letter = sweep.columns.get(f"{model.output}_deg")
    rows = range(sweep.rows[0], sweep.rows[1] + 1)
    return [values.get((sweep.sheet, f"{letter}{r}")) for r in rows]


def _in_shown_window(degrees: np.ndarray, shown: list) -> np.ndarray:
    """The reference's angles, each moved by whole turns next to the book's value in its row:
    the 360° window is the book's presentation (judged by the window check), the values are
    the reference's."""
    out = np.array(degrees, dtype=float)
    for i, v in enumerate(shown):
        if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) \
                and math.isfinite(out[i]):
            out[i] += 360.0 * round((float(v) - out[i]) / 360.0)
    return out


def _summary_expected(model, solver, params, ref, closes, starts, ends,
                      shown_output=None) -> dict:
    out: dict[str, object] = {
        "assembles_all": "yes" if closes.all() else "no",
        "not_closing": float((~closes).sum()),
        # the first loop step, in order, where the reference finds no assembly on some row
        "failing_step": next((name for key, (_, name) in zip(model.closes, model.loop_steps)
                              if not np.isfinite(np.asarray(ref[key], dtype=float)).all()),
                             DASH),
    }
    gap_starts = sorted(x for x in starts if x != DASH)
    gap_ends = sorted(x for x in ends if x != DASH)
    for k in range(1, layout.GAPS_SHOWN + 1):
        out[f"gap{k}_from"] = gap_starts[k - 1] if k <= len(gap_starts) else DASH
        out[f"gap{k}_to"] = gap_ends[k - 1] if k <= len(gap_ends) else DASH
    if model.output:
        o = np.asarray(ref[model.output], dtype=float)
        if shown_output is not None:            # an angle: in degrees, in the book's window
            o = _in_shown_window(np.degrees(o), shown_output)
        out["output_min"], out["output_max"] = _extreme(o, np.min), _extreme(o, np.max)
        if shown_output is not None:
            out["output_swing"] = (DASH if out["output_min"] == DASH
                                   else out["output_max"] - out["output_min"])
    for i, key in enumerate(model.transmissions, start=1):
        m = np.degrees(np.asarray(ref[key], dtype=float))
        n = summary_prefix("mu", i)
        out[f"{n}_min"], out[f"{n}_max"] = _extreme(m, np.min), _extreme(m, np.max)
    for i, (g, c, k, r) in enumerate(solver.fourbar_loops(params)):
        n = summary_prefix("", i + 1)
        if not all(math.isfinite(v) for v in (g, c, k, r)):
            # a synthesis that designed no linkage: #N/A for its lengths and Grashof class
            out.update({f"fb{n}_ground": g, f"fb{n}_crank": c, f"fb{n}_coupler": k,
                        f"fb{n}_rocker": r, f"grashof{n}": math.nan})
            # the limit angles' cells catch every error as "none": there are none
            out.update({f"limit{n}_{name}_{end}": "none" for name in ("stretched", "folded")
                        for end in (1, 2)})
            continue
        out.update({f"fb{n}_ground": g, f"fb{n}_crank": c, f"fb{n}_coupler": k,
                    f"fb{n}_rocker": r, f"grashof{n}": generic.grashof_class(g, c, k, r)})
        for name, length in (("stretched", k + r), ("folded", abs(k - r))):
            roots = solver.limit_angles(params, length, i)
            lo, hi = (roots[0], roots[-1]) if roots else ("none", "none")
            out[f"limit{n}_{name}_1"], out[f"limit{n}_{name}_2"] = lo, hi
    return out

