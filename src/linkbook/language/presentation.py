"""What the description asks of the drawing and the summary: the links drawn, the traced point,
the main output, the transmission angles, the four-bar loops on the ground, the columns' order
and the charts. Read after the steps, from what they placed (the compiler's points and links).
"""
from __future__ import annotations

from .excel import ATOM, PRODUCT, SUM, direction, minus, radians
from .fields import as_table, as_text, check_keys
from .model import COLUMN, LENGTH, RAD, Chart, DescriptionError, FourBarLoop, Joint
from .schema import keys_of, schema

CHART_KEYS = keys_of(schema()["properties"]["mechanism"]["properties"]["charts"]["items"])


class Presentation:
    """Reads the description's drawing, outputs and charts into the compiler's model."""

    def __init__(self, compiler):
        self.c = compiler
        self.field = compiler.field

    def read(self, d: dict) -> None:
        m = self.c.model
        shown = {q.key: q for q in m.of_role(COLUMN)}
        links = d["links"]
        if not isinstance(links, list) or not links:
            raise DescriptionError(f"{self.field}.links", "must be a list of point lists")
        for i, link in enumerate(links):
            where = f"{self.field}.links[{i}]"
            if not isinstance(link, list) or len(link) < 2:
                raise DescriptionError(where, f"must list two or more points (got {link!r})")
            for j, name in enumerate(link):
                if not isinstance(name, str) or name not in self.c.points:
                    raise DescriptionError(f"{where}[{j}]", f"point {name!r} is not defined")
            m.links.append(tuple(link))
        used = list(dict.fromkeys(n for link in m.links for n in link))
        m.joints = [Joint(n, *(p.text for p in self.c.points[n])) for n in used]
        m.ground = tuple(n for n in used if n in self.c.ground)
        if "trace" in d:
            t = d["trace"]
            if not isinstance(t, str) or t not in self.c.points or t in self.c.ground:
                raise DescriptionError(f"{self.field}.trace", f"must be a moving point "
                                                              f"(got {t!r})")
            x, y = (e.text[1:-1] for e in self.c.points[t])
            if x not in shown or y not in shown:
                raise DescriptionError(f"{self.field}.trace", f"{t}'s coordinates must be "
                                                              "shown columns")
            m.path = (x, y)
            self.c.traced = t
        if "output" in d:
            out = d["output"]
            q = shown.get(out) if isinstance(out, str) else None
            if q is None or q.unit not in (LENGTH, RAD):
                raise DescriptionError(f"{self.field}.output", f"{out!r} is not a shown column "
                                                               "of a length or an angle")
            if q.unit == RAD and not q.in_degrees:
                # its smallest and largest value are read in its degree view, whose window
                # keeps the swing in one piece
                raise DescriptionError(f"{self.field}.output", f"the angle {out!r} needs its "
                                                               "degree view (degrees = true)")
            m.output = out
        m.transmissions = self.transmissions(d.get("transmission"), shown)
        m.fourbars = self.fourbar_loops()
        if "columns" in d:
            self.reorder(d["columns"])
        m.charts = self.charts(d.get("charts"), shown)

    def transmissions(self, given: object, shown: dict) -> tuple[str, ...]:
        """The transmission angles the summary reports: those named (a key or a list of keys of
        shown angle columns in [0, π]), by default μ of every dyad that shows it."""
        if given is None:
            return tuple(dy["mu"].key for dy in self.c.dyads if dy["mu"].shown)
        keys = [given] if isinstance(given, str) else given
        field = f"{self.field}.transmission"
        if not isinstance(keys, list):
            raise DescriptionError(field, "must be a column key or a list of them")
        for k in keys:
            if not isinstance(k, str) or k not in shown or shown[k].unit != RAD:
                # its smallest and largest value are read in radians: an angle in [0, π]
                raise DescriptionError(field, f"{k!r} is not a shown column of an angle")
        return tuple(keys)

    def fourbar_loops(self) -> tuple[FourBarLoop, ...]:
        """Every dyad with one end a ground point and the other the pin of a crank about a
        ground point: a four-bar loop on the ground, whose Grashof class and limit angles the
        summary reports.  The output link is the dyad's side at the ground point."""
        loops = []
        for dy in self.c.dyads:
            for pin, fixed, coupler, rocker in ((dy["p"], dy["q"], "p_length", "q_length"),
                                                (dy["q"], dy["p"], "q_length", "p_length")):
                pivot = self.c.crank_of.get(pin)
                if fixed in self.c.ground and pivot in self.c.ground:
                    loops.append(self.fourbar(pivot, pin, dy, fixed, coupler, rocker))
                    break
        return tuple(loops)

    def fourbar(self, pivot: str, pin: str, dy: dict, fixed: str, coupler: str,
                rocker: str) -> FourBarLoop:
        crank = next(c for c in self.c.cranks if c["point"] == pin)
        (ox, oy), (qx, qy) = self.c.points[pivot], self.c.points[fixed]
        dx, dy_ = minus(qx, ox), minus(qy, oy)
        ground = (f"ABS({dx.text})" if dy_.zero else f"ABS({dy_.text})" if dx.zero
                  else f"SQRT({dx.at_least(ATOM)}^2+{dy_.at_least(ATOM)}^2)")
        angle = direction(dx, dy_).at_least(SUM)
        if not crank["phase"].zero:
            angle = f"{angle}-{radians(crank['phase']).at_least(PRODUCT)}"
        return FourBarLoop(ground, crank["length"].text, dy[coupler].text, dy[rocker].text,
                           angle, f"{pivot} {pin} {dy['point']} {fixed}")

    def reorder(self, order: object) -> None:
        field = f"{self.field}.columns"
        shown = [q.key for q in self.c.model.of_role(COLUMN) if q.key != self.c.input_key]
        if not isinstance(order, list) or sorted(order, key=str) != sorted(shown):
            missing = [k for k in shown if not isinstance(order, list) or k not in order]
            extra = [k for k in order if k not in shown] if isinstance(order, list) else []
            raise DescriptionError(field, "must list every shown column once"
                                   + (f"; missing {', '.join(missing)}" if missing else "")
                                   + (f"; unknown {', '.join(map(str, extra))}" if extra else ""))
        rank = {k: i for i, k in enumerate([self.c.input_key, *order])}
        qs = self.c.model.quantities
        columns = sorted((q for q in qs if q.role == COLUMN), key=lambda q: rank[q.key])
        it = iter(columns)
        self.c.model.quantities = [next(it) if q.role == COLUMN else q for q in qs]

    def charts(self, raw: object, shown: dict) -> list[Chart]:
        field = f"{self.field}.charts"
        symbol_of = {**{k: q.symbol for k, q in shown.items()},
                     **{f"{k}_deg": q.symbol for k, q in shown.items() if q.in_degrees},
                     self.c.input_column: self.c.input_symbol}
        if raw is None:
            return self.default_charts(shown)
        if not isinstance(raw, list):
            raise DescriptionError(field, "must be a list of charts")
        out = []
        for i, c in enumerate(raw):
            where = f"{field}[{i}]"
            c = as_table(where, c)
            check_keys(where, c, *CHART_KEYS)
            ys = c["y"] if isinstance(c["y"], list) else [c["y"]]
            if not ys:
                raise DescriptionError(f"{where}.y", "must name at least one column to plot")
            for k in [c["x"], *ys]:
                if not isinstance(k, str) or k not in symbol_of:
                    raise DescriptionError(where, f"{k!r} is not a column; columns are "
                                                  f"{', '.join(symbol_of)}")
            x_title = c.get("x_title", symbol_of[c["x"]])
            y_title = c.get("y_title", ", ".join(symbol_of[k] for k in ys))
            out.append(Chart(as_text(f"{where}.title", c["title"]), c["x"], tuple(ys),
                             as_text(f"{where}.x_title", x_title),
                             as_text(f"{where}.y_title", y_title),
                             bool(c.get("equal_axes", False))))
        return out

    def default_charts(self, shown: dict) -> list[Chart]:
        """Without charts in the description: every degree column against the input angle, and
        the traced point's path."""
        degs = tuple(f"{k}_deg" for k, q in shown.items() if q.in_degrees)
        charts = []
        if degs:
            charts.append(Chart("Link angles", self.c.input_column, degs, self.c.input_symbol,
                                "angle [deg]"))
        if self.c.model.path:
            px, py = self.c.model.path
            charts.append(Chart(f"Path of {px[1:]}", px, (py,), px, py, equal_axes=True))
        return charts
