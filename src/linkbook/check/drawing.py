"""The judge of the drawing: the joints table, the drawing's rows and the links it draws (each
joins two points the reference knows are joined), and each equal-scale frame (its extents,
centre, grid square and legend, and every mapped cell) by the documented rule of a live frame."""
from __future__ import annotations

import math

import numpy as np

from . import reference as generic
from ..base import sheets as layout
from ..base.record import Frame, Series
from ..base.xlsx import column_cells
from .checks import Check, Mismatch, compare_exact, expected_of
from .context import Judging

# The rule of a live frame (docs/mechanisms.md, "Drawings"), restated here from the documented
# convention: the frame is centred on the extents of what a chart draws, and a grid square is
# the smallest 1, 2 or 5 × 10ⁿ that fits MARGIN times the larger extent in 2·HALF squares.
FRAME_HALF, FRAME_MARGIN = 5, 1.12
FRAME_SQUARES = (1.0, 2.0, 5.0, 10.0)


def check_drawing(j: Judging) -> None:
    """The joints table, the drawing rows (the sliders' guides and blocks the reference's,
    sized in the drawing's grid square), the drawn links and the frames."""
    pos = j.record.position
    joint_values = {name: (float(x[0]), float(y[0])) for name, (x, y) in j.one["points"].items()}
    for joint in j.model.joints:
        x_cell, y_cell = pos.joints[joint.name]
        j.run("joints", joint.name, pos.sheet, [x_cell, y_cell],
              np.array(joint_values[joint.name]), "length",
              _joint_slope(j, [(joint.name, 0), (joint.name, 1)]))
    joints = {joint.name: joint_values[joint.name] for joint in j.model.joints}  # the table's
    drawn, over_sweep, free = dict(joint_values), j.ref, set()
    if j.record.frames is not None:
        description = j.solver.description
        square = _drawing_square(j, joints)
        sliders = generic.slider_drawing(description, j.params, j.ref, j.one, square)
        drawn.update({name: (float(x[0]), float(y[0])) for name, (x, y) in sliders.items()})
        over_sweep = {**j.ref, "points": {**j.ref["points"], **generic.slider_drawing(
            description, j.params, j.ref, j.ref, square)}}
        free = _undetermined_guide_ends(j)
        drawn.update({name: (math.nan, math.nan) for name in free})
    drawing_cells, drawing_expected, dead, coordinates = [], [], [], []
    for link in pos.drawing:
        for i, name in enumerate(link.joints):
            r = link.rows[0] + i
            drawing_cells += [f"N{r}", f"O{r}"]
            drawing_expected += list(drawn.get(name, (math.nan, math.nan)))
            dead += [name in free] * 2
            coordinates += [(name, 0), (name, 1)]
    j.run("joints", "drawing rows", pos.sheet, drawing_cells, np.array(drawing_expected),
          "length", _joint_slope(j, coordinates), dead=np.array(dead))
    j.checks.append(_check_links(j, over_sweep))
    if j.record.frames is not None and j.own_inputs:
        j.checks += _check_frames(j, joints, drawn, free)


def _undetermined_guide_ends(j: Judging) -> set[str]:
    """The ends of each guide whose block's travel over the sweep reaches a row in round-off
    beyond any bound (Check.beyond_rounding: a lever parallel to the line it should meet): the
    guide runs to the smallest and largest travel, which are then not determined (#N/A or any
    number, as a rate at a dead centre)."""
    c = Check("joints", "drawing rows", j.size, 1.0, j.size)
    out = set()
    for label, mover in generic.guide_movers(j.solver.description).items():
        if any(c.beyond_rounding(v) for v in j.ref["points"][mover]):
            out |= {f"{label} 1", f"{label} 2"}
    return out


def joined_pairs(description: dict, ref: dict, size: float) -> set[frozenset]:
    """Pairs of points the reference knows are joined, found without the description's list of
    links: a step's new point and each point the step names (a crank's pivot, a dyad's two
    ends, a slider's line, an actuator's ends; a vector's two ends), any two points of one
    slider's guide or of one block (generic.slider_parts), any two ground points (link 1, even
    where a synthesis designed no place for them: NaN) and any two points whose distance
    never changes over the sweep (a rigid link)."""
    pairs = {frozenset((a, b)) for part in generic.slider_parts(description)
             for a in part for b in part if a != b}
    ground = [name for name in description.get("ground", {}) if isinstance(name, str)]
    pairs.update(frozenset((a, b)) for a in ground for b in ground if a != b)
    for step in description.get("steps", []):
        if not isinstance(step, dict):
            continue
        named = _point_names({k: v for k, v in step.items()
                              if k not in ("point", "columns", "type", "key")})
        if isinstance(step.get("point"), str):
            pairs.update(frozenset((step["point"], name)) for name in named)
        else:       # a vector (from, to): the two points it measures between
            pairs.update(frozenset((a, b)) for a in named for b in named if a != b)
    points = ref.get("points", {})
    names = sorted(points)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            (xa, ya), (xb, yb) = points[a], points[b]
            d = np.hypot(np.asarray(xa, float) - xb, np.asarray(ya, float) - yb)
            d = d[np.isfinite(d)]
            if d.size and np.ptp(d) <= 1e-9 * size:
                pairs.add(frozenset((a, b)))
    return pairs


def _point_names(value) -> list[str]:
    if isinstance(value, str):
        return [value]
    if isinstance(value, dict):
        return [n for v in value.values() for n in _point_names(v)]
    if isinstance(value, list):
        return [n for v in value for n in _point_names(v)]
    return []


def _check_links(j: Judging, ref: dict) -> Check:
    """Each segment the drawing draws joins two points the reference knows are joined (a check
    of the drawing's structure: its cells are compared in "drawing rows")."""
    pos = j.record.position
    c = Check("joints", "drawn links", j.size)
    joined = joined_pairs(j.solver.description, ref, j.size)
    x_col = layout.DRAWING_COLUMNS[0]
    for link in pos.drawing:
        names = link.joints
        for i, (a, b) in enumerate(zip(names, names[1:])):
            if a != b and frozenset((a, b)) not in joined:
                c.mismatches.append(Mismatch(pos.sheet, f"{x_col}{link.rows[0] + i + 1}",
                                             "a link between joined points",
                                             f"{a}–{b}, which nothing joins"))
    return c


# ---------------------------------------------------------------- frames
def frame_squares(need: float) -> list[tuple[float, float]]:
    """(power of ten, grid square) for `need` per square; two when `need` is within rounding of
    a step (1, 2, 5 × 10ⁿ), where either evaluation may fall on either side."""
    out = []
    for r in (need * (1 - 1e-9), need, need * (1 + 1e-9)):
        decade = 10.0 ** math.floor(math.log10(r))
        square = decade * next(m for m in FRAME_SQUARES if r <= m * decade * (1 + 1e-15))
        if (decade, square) not in out:
            out.append((decade, square))
    return out


def _frame_extents(j: Judging, frame: Frame, joint_values: dict) -> tuple[dict, dict]:
    """The least and greatest x and y of what a frame holds (the reference's); NaN on an axis
    where a value is beyond rounding (Check.beyond_rounding: its extreme is not determined)."""
    ext = frame.extent
    judge = Check("frame", "extents", j.size, 1.0, j.size)
    lo, hi = {}, {}
    for i, axis in enumerate("xy"):
        parts = [expected_of(j.ref, key) for key in getattr(ext, axis)]
        if ext.position:
            parts.append(np.array([xy[i] for xy in joint_values.values()]))
        v = np.concatenate(parts) if parts else np.array([])
        v = v[np.isfinite(v)]
        lo[axis], hi[axis] = (float(v.min()), float(v.max())) if v.size else (0.0, 0.0)
        if judge.beyond_rounding(v):
            lo[axis] = hi[axis] = math.nan
    return lo, hi


def _need(ext: dict) -> float:
    """The size a grid square must hold, by the rule, for a frame's extents."""
    return max(ext["xmax"] - ext["xmin"], ext["ymax"] - ext["ymin"], 1e-12) \
        * FRAME_MARGIN / (2 * FRAME_HALF)


def _drawing_square(j: Judging, joint_values: dict) -> float:
    """The drawing's grid square by the rule, from the book's extents (each judged against the
    reference's; where the need is within rounding of a step, the one the book chose)."""
    frames = j.record.frames
    frame = frames.frames[0]
    lo, hi = _frame_extents(j, frame, joint_values)
    need = _need(_book_extents(j, frames.sheet, frame.cells, lo, hi))
    options = [square for _, square in frame_squares(need)]
    got = j.values.get((frames.sheet, frame.cells["square"]))
    return next((o for o in options if isinstance(got, (int, float))
                 and abs(got - o) <= 1e-12 * o), options[0])


def _check_frames(j: Judging, joint_values: dict, drawn: dict, free: set[str]
                  ) -> list[Check]:
    """Each equal-scale chart's frame (extents, centre, grid square, the scale bar's legend)
    from the reference's points (`joint_values`: the joints table's), and each mapped cell:
    the reference's coordinate in squares of that frame (`drawn`: every drawn point's; `free`:
    the drawn points that are not determined)."""
    sheet = j.record.frames.sheet
    checks = []
    for frame in j.record.frames.frames:
        name = "drawing" if frame.chart is None else f"chart {frame.chart + 1}"
        cells = frame.cells
        lo, hi = _frame_extents(j, frame, joint_values)
        # the extents against the reference; the centre and the need by the rule from the
        # book's own extents (each within its bound of the reference's): near a position where
        # a point runs far out, the two extents carry the rounding of that position, which their
        # half-sum (the centre, often near 0) must not be judged without
        ext = _book_extents(j, sheet, cells, lo, hi)
        centre = {"x": (ext["xmin"] + ext["xmax"]) / 2, "y": (ext["ymin"] + ext["ymax"]) / 2}
        need = _need(ext)
        expected = {"xmin": lo["x"], "xmax": hi["x"], "ymin": lo["y"], "ymax": hi["y"],
                    "cx": centre["x"], "cy": centre["y"], "need": need}
        c = Check("frame", f"{name}: extents", j.size, 1.0, j.size)
        keys = list(expected)
        dead = np.array([k in ("xmin", "xmax", "ymin", "ymax") and math.isnan(expected[k])
                         for k in keys])
        j.compare(c, sheet, [cells[k] for k in keys], np.array([expected[k] for k in keys]),
                  "length", dead=dead)
        checks.append(c)
        square_check, square = _check_square(j, sheet, cells, need, name)
        checks.append(square_check)
        for s in frame.series:
            checks += _check_mapped(j, sheet, s, drawn, centre, square, f"{name}: {s.title}",
                                    free)
    return checks


def _book_extents(j: Judging, sheet: str, cells: dict, lo: dict, hi: dict) -> dict:
    """The book's extents of a frame, each where it is a number, else the reference's."""
    ref = {"xmin": lo["x"], "xmax": hi["x"], "ymin": lo["y"], "ymax": hi["y"]}
    out = {}
    for key, value in ref.items():
        got = j.values.get((sheet, cells[key]))
        number = isinstance(got, (int, float)) and not isinstance(got, bool) \
            and math.isfinite(got)
        out[key] = float(got) if number else value
    return out


def _check_square(j: Judging, sheet: str, cells: dict, need: float, name: str
                  ) -> tuple[Check, float]:
    """The power of ten and the grid square: the rule's choice for the reference's `need`
    (either one at a step); the legend's text names the square the book chose."""
    c = Check("frame", f"{name}: grid square", j.size, 1.0, j.size)
    options = frame_squares(need)
    got = tuple(j.values.get((sheet, cells[k])) for k in ("decade", "square"))
    chosen = next((o for o in options if all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and abs(v - e) <= 1e-12 * e
        for v, e in zip(got, o))), None)
    for k, v, e in zip(("decade", "square"), got, options[0]):
        c.cells += 1
        c.judged.add((sheet, cells[k]))
        if chosen is None:
            c.mismatches.append(Mismatch(sheet, cells[k], " or ".join(
                f"{o[k == 'square']:g}" for o in options), v))
    square = (chosen or options[0])[1]
    places = max(0, -math.floor(round(math.log10(square), 6)))
    compare_exact(c, sheet, [cells["label"]], j.got(sheet, [cells["label"]]),
                  [f"grid square {square:.{places}f} {j.record.length_unit}"])
    return c, square


def _joint_slope(j: Judging, coordinates: list[tuple[str | None, int]], per: float = 1.0):
    """slope(i) for checks.compare: |∂/∂θ| at the current position of cell i's joint
    coordinate (name, axis 0 for x, 1 for y), from the reference's column of that coordinate,
    divided by `per` (a drawing's square); 0 for a point with no such column (a fixed pivot, a
    guide's end) or none."""
    now = np.array([j.angle])

    def slope(i: int) -> float:
        name, axis = coordinates[i]
        key = f"{'xy'[axis]}{name}"
        points = j.one["points"]
        if name not in points or key not in j.one or \
                float(j.one[key][0]) != float(points[name][axis][0]):
            return 0.0
        return j.slope(now, key, "length")(0) / per
    return slope


def _check_mapped(j: Judging, sheet: str, series: Series, joint_values: dict, centre: dict,
                  square: float, name: str, free: set[str]) -> list[Check]:
    """A mapped column pair: (coordinate − centre) / square, the coordinate the reference's
    (a joint at the current position, or a sweep column at the sweep's angles), judged with the
    bound of a length scaled to squares."""
    first, last = series.mapped_rows
    out = []
    for i, axis in enumerate("xy"):
        letter = series.columns[i]
        cells = column_cells(letter, first, last)
        slope, dead = None, None
        if series.kind == "links":
            world, dead = np.full(len(cells), np.nan), np.zeros(len(cells), dtype=bool)
            coordinates = [(None, i)] * len(cells)
            for link in j.record.position.drawing:
                for k, joint in enumerate(link.joints):
                    row = link.rows[0] + k - series.rows[0]
                    world[row] = joint_values.get(joint, (math.nan, math.nan))[i]
                    dead[row] = joint in free
                    coordinates[row] = (joint, i)
            slope = _joint_slope(j, coordinates, square)
        else:
            key = getattr(series, axis)
            world = expected_of(j.ref, key)
            if key in j.slopes:
                slope = (lambda f: lambda k: f(k) / square)(j.slopes[key])
        c = Check("frame", f"{name} {axis}", j.size, 1.0, j.size / square)
        j.compare(c, sheet, cells, (world - centre[axis]) / square, "-", slope, dead)
        out.append(c)
    return out
