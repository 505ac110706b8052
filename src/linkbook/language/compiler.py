"""The mechanism language (docs/language.md): a mechanism described as data, compiled into the
model the workbook writer lays out, one step type of the steps package per step.

Every problem with a description raises InputError naming the step and the field, before any file
is touched. Nothing here touches openpyxl, and nothing here is used by the reference solver.
"""
from __future__ import annotations

import keyword

from ..base.xlsx import excel_name_problem
from .columns import Column, Sym, input_angle
from .dynamics import check_dynamics
from .excel import ATOM, SUM, Expr, direction, key, minus, references
from .expressions import expression
from .fields import IDENT, POINT_NAME, RESERVED_KEYS, as_table, as_text, check_keys
from .mechanisms import (ANGLE_KIND, BRANCH_KIND, LENGTH_KIND, LOAD_UNITS, MOTION_SYMBOLS,
                         OFFSET_KIND, RATE_KIND, Mechanism)
from .model import (ALIAS, COLUMN, CONSTANT, LENGTH, RAD, Block, DescriptionError, Guide, Model,
                    Quantity)
from .forces import ForceWriter
from .motion import MotionWriter, readable_rates
from .presentation import Presentation
from .schema import keys_of, schema
from .steps import COMMON_KEYS, STEPS

KINDS = (LENGTH_KIND, OFFSET_KIND, ANGLE_KIND, BRANCH_KIND, *LOAD_UNITS)
MECHANISM_KEYS = keys_of(schema()["properties"]["mechanism"])
FORCE_KEYS = ("bodies", "loads", "dynamics")    # any of them: the book has a Forces sheet


class Compiler:
    """Walks a description once, in order, building the model and checking every reference."""

    def __init__(self, data: dict, kinds: dict[str, str], origin: str):
        self.origin = origin
        self.kinds = dict(kinds)
        self.symbols = set(kinds)
        self.model = Model()
        self.points: dict[str, tuple[Expr, Expr]] = {}
        self.ground: set[str] = set()
        self.crank_of: dict[str, str] = {}              # crank point -> its pivot
        self.rigid: dict[tuple[str, str], tuple[Expr | None, Expr]] = {}  # (A, B) -> |AB|, angle(A→B)
        self.cranks: list[dict] = []
        self.dyads: list[dict] = []
        self.input_kind = ANGLE_KIND
        self.swept: set[str] = set()     # the input key, where it is a length expressions use
        self.records: list[dict] = []    # per step what it placed, for its rates (motion.py)
        self.lengths: list[tuple[str, object]] = []   # (field, expression) of every length
        self.loads: list[tuple[str, object]] = []     # ... of every value of the force analysis
        self.traced = ""
        self.field = f"{origin}: mechanism"
        self.data = as_table(self.field, data)

    # -- helpers
    @property
    def input_column(self) -> str:
        return f"{self.input_key}_deg" if self.input_kind == ANGLE_KIND else self.input_key

    def expr(self, field: str, raw: object) -> Expr:
        return expression(field, raw, self.symbols)

    def frame(self, field: str, raw: object, defining: str) -> tuple[str, str]:
        """[A, B]: two different known points (a link's frame)."""
        if not isinstance(raw, list) or len(raw) != 2:
            raise DescriptionError(field, f"must be [A, B], two known points (got {raw!r})")
        a = self.known_point(f"{field}[0]", raw[0], defining)
        b = self.known_point(f"{field}[1]", raw[1], defining)
        if a == b:
            raise DescriptionError(field, "needs two different points")
        return a, b

    def known_point(self, field: str, name: object, defining: str = "") -> str:
        if not isinstance(name, str):
            raise DescriptionError(field, f"must be a point name (got {name!r})")
        if name == defining:
            raise DescriptionError(field, f"{name!r} is the point this step defines (a cyclic "
                                          "definition)")
        if name not in self.points:
            steps = self.data.get("steps")
            later = isinstance(steps, list) and any(
                isinstance(s, dict) and s.get("point") == name for s in steps)
            why = "is defined by a later step" if later else "is not defined"
            raise DescriptionError(field, f"point {name!r} {why}; known so far: "
                                          f"{', '.join(self.points) or 'none'}")
        return name

    def branch(self, field: str, raw: object) -> str:
        """A branch: a parameter of kind branch, or the number 1 or −1 (an alias of it)."""
        if isinstance(raw, str) and raw in self.kinds:
            if self.kinds[raw] != BRANCH_KIND:
                raise DescriptionError(field, f"{raw!r} is a parameter of kind "
                                              f"{self.kinds[raw]}, not a branch")
            return raw
        if isinstance(raw, bool) or raw not in (1, -1):
            raise DescriptionError(field, f"must be 1, -1 or a branch parameter (got {raw!r})")
        name = "_plus_one" if raw == 1 else "_minus_one"   # no user symbol starts with _
        if not any(q.key == name for q in self.model.quantities):
            self.model.add(Quantity(name, str(int(raw)), "-", str(int(raw)), ALIAS))
        return name

    def operand(self, hint: str, e: Expr) -> str:
        """A key standing for an expression: the parameter itself, or an alias of the text (its
        key starts with _, which no user symbol or column key does)."""
        inner = e.text[1:-1]
        if e.text.startswith("{") and e.text.endswith("}") and inner in self.symbols:
            return inner
        self.model.add(Quantity(f"_{hint}", hint, LENGTH, e.text, ALIAS))
        return f"_{hint}"

    def length_operand(self, field: str, hint: str, e: Expr, raw: object) -> str:
        """A key standing for a length the loop is closed with. The template's value must be
        positive (checked at build: `self.lengths`); in the book, where the inputs make it zero
        or negative the loop cannot be assembled and the cells that use it are #N/A, as the
        reference says (a length parameter itself needs no guard: its cell refuses a
        non-positive value, and so does the swept input's)."""
        self.lengths.append((field, raw))
        inner = e.text[1:-1]
        bare = e.text.startswith("{") and e.text.endswith("}")
        if "{" not in e.text or bare and (self.kinds.get(inner) == LENGTH_KIND
                                          or inner in self.swept):
            return self.operand(hint, e)
        guarded = f"IF({e.at_least(SUM)}>0,{e.text},NA())"
        self.model.add(Quantity(f"_{hint}", hint, LENGTH, guarded, ALIAS))
        return f"_{hint}"

    def columns(self, field: str, step: dict, defaults: list[Column]) -> dict[str, Sym]:
        """The step's columns after its `columns` table renamed or hid them."""
        given = step.get("columns", {})
        given = as_table(f"{field}.columns", given)
        names = {c.name for c in defaults}
        for name in given:
            if name not in names:
                raise DescriptionError(f"{field}.columns.{name}",
                                       f"this step writes no such column; it writes "
                                       f"{', '.join(c.name for c in defaults)}")
        out = {}
        for c in defaults:
            spec = given.get(c.name, {})
            where = f"{field}.columns.{c.name}"
            if spec is False:
                out[c.name] = Sym(c.key, c.symbol, c.label, shown=False)
                continue
            if spec is True:
                spec = {}
            spec = as_table(where, spec)
            check_keys(where, spec, set(), {"key", "symbol", "label", "degrees", "wrap", "shown"})
            k = self.new_key(f"{where}.key", spec.get("key", c.key))
            degrees, wrap = spec.get("degrees", c.degrees), spec.get("wrap", False)
            shown = spec.get("shown", True)
            for flag, v in (("degrees", degrees), ("wrap", wrap), ("shown", shown)):
                if not isinstance(v, bool):
                    raise DescriptionError(f"{where}.{flag}", "must be true or false")
            out[c.name] = Sym(k, as_text(f"{where}.symbol", spec.get("symbol", c.symbol)),
                              as_text(f"{where}.label", spec.get("label", c.label)),
                              deg=degrees and c.unit == RAD, wrap=wrap,
                              shown=shown and (c.shown or c.name in given))
        return out

    def new_key(self, field: str, k: object) -> str:
        """A column key: an identifier that no parameter, degree view or bookkeeping column has."""
        if not isinstance(k, str) or not IDENT.match(k) or keyword.iskeyword(k):
            raise DescriptionError(field, f"must be letters, digits and _, starting with a "
                                          f"letter (got {k!r})")
        if k in self.symbols or k.endswith("_deg") or k in RESERVED_KEYS:
            raise DescriptionError(field, f"{k!r} is taken (a parameter, a degree view or a "
                                          "bookkeeping column)")
        return k

    def add_point(self, field: str, name: str, sx: Sym, sy: Sym, x: str, y: str) -> None:
        self.model.add(Quantity(sx.key, sx.symbol, LENGTH, x, COLUMN if sx.shown else ALIAS,
                                sx.label),
                       Quantity(sy.key, sy.symbol, LENGTH, y, COLUMN if sy.shown else ALIAS,
                                sy.label))
        self.points[name] = (key(sx.key), key(sy.key))

    def slides_on(self, n: str, kind: str, origin: str, direction: tuple[str, str],
                  travel: Sym) -> None:
        """The line a block of step `n` slides on, drawn over the block's travel: the sweep's
        column of its position along the line from `origin` (a hidden column: no guide)."""
        if travel.shown:
            ox, oy = self.points[origin]
            self.model.guides.append(Guide(n, kind, ox.text, oy.text, *direction, travel.key))

    def block(self, centre: str, direction: tuple[str, str]) -> None:
        """A block pivoted on the point `centre`, its long side along the line it slides on."""
        cx, cy = self.points[centre]
        self.model.blocks.append(Block(centre, cx.text, cy.text, *direction))

    def angle_of(self, a: str, b: str, field: str, step: bool = True) -> Expr:
        """angle(A→B) of the frame `field` names, as Excel text: a known link's angle column,
        or the direction of the points, #N/A where they meet (model.frames: build refuses a
        step's frame whose points meet on every row, and warns of another's)."""
        if (a, b) in self.rigid:
            return self.rigid[(a, b)][1]
        if (b, a) in self.rigid:
            return Expr(f"{self.rigid[(b, a)][1].at_least(SUM)}+PI()", SUM)
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        self.model.frames.append((field, a, b, step))
        return direction(minus(bx, ax), minus(by, ay))

    def length_of(self, a: str, b: str) -> Expr:
        """|AB|: a known link's length, or the distance of the points."""
        for pair in ((a, b), (b, a)):
            if pair in self.rigid and self.rigid[pair][0] is not None:
                return self.rigid[pair][0]
        (ax, ay), (bx, by) = self.points[a], self.points[b]
        dx, dy = minus(bx, ax), minus(by, ay)
        return Expr(f"SQRT({dx.at_least(ATOM)}^2+{dy.at_least(ATOM)}^2)")

    # -- the whole description
    def run(self) -> Model:
        d = self.data
        check_keys(self.field, d, *MECHANISM_KEYS)
        self.model.where = self.field
        self.read_input(d["input"])
        self.read_ground(d["ground"])
        steps = d["steps"]
        if not isinstance(steps, list) or not steps:
            raise DescriptionError(f"{self.field}.steps", "must be a non-empty list of steps")
        for i, step in enumerate(steps):
            self.read_step(i, step)
        steps_keys = {q.key for q in self.model.quantities}   # what an expression step may name
        self.model.where = self.field
        Presentation(self).read(d)
        motion = MotionWriter(self)
        motion.run()
        # last: a problem of the steps explains more
        check_dynamics(self, d, steps_keys | readable_rates(self.model))
        if any(k in d for k in FORCE_KEYS):
            ForceWriter(self, motion).run()
        return self.model

    def read_input(self, raw: object) -> None:
        field = f"{self.field}.input"
        table = as_table(field, raw)
        check_keys(field, table, {"key", "symbol"}, {"kind"})
        k = table["key"]
        if not isinstance(k, str) or not IDENT.match(k) or k in self.symbols \
                or k.endswith("_deg"):
            raise DescriptionError(f"{field}.key", f"must be a new identifier not ending in _deg "
                                                   f"(got {k!r})")
        self.input_kind = table.get("kind", ANGLE_KIND)
        if self.input_kind not in (ANGLE_KIND, LENGTH_KIND):
            raise DescriptionError(f"{field}.kind", f"must be {ANGLE_KIND} (a crank's angle) or "
                                                    f"{LENGTH_KIND} (a linear actuator's length) "
                                                    f"(got {self.input_kind!r})")
        problem = excel_name_problem(f"{k}_now")
        if problem:
            raise DescriptionError(f"{field}.key", f"{k}_now (its Excel name) {problem}")
        self.input_key, self.input_symbol = k, as_text(f"{field}.symbol", table["symbol"])
        if self.input_kind == ANGLE_KIND:
            input_angle(self.model, k, self.input_symbol)
        else:   # the swept length is the sweep's first column itself; a dyad's side may be it
            self.swept = {k}
        self.motion_symbols = MOTION_SYMBOLS[self.input_kind]
        for symbol in self.motion_symbols:    # the input's speed and acceleration
            self.kinds[symbol] = RATE_KIND
            self.symbols.add(symbol)

    def read_ground(self, raw: object) -> None:
        field = f"{self.field}.ground"
        table = as_table(field, raw)
        if not table:
            raise DescriptionError(field, "needs at least one fixed point")
        for name, xy in table.items():
            where = f"{field}.{name}"
            self.check_new_point(where, name)
            if not isinstance(xy, list) or len(xy) != 2:
                raise DescriptionError(where, f"must be [x, y] (got {xy!r})")
            self.points[name] = (self.expr(f"{where}[0]", xy[0]), self.expr(f"{where}[1]", xy[1]))
            self.ground.add(name)

    def check_new_point(self, field: str, name: object) -> None:
        if not isinstance(name, str) or not POINT_NAME.match(name):
            raise DescriptionError(field, f"a point name must be letters, digits and _ "
                                          f"(got {name!r})")
        if name in self.points:
            raise DescriptionError(field, f"point {name!r} is defined twice")

    def read_step(self, i: int, raw: object) -> None:
        field = f"{self.field}.steps[{i}]"
        step = as_table(field, raw)
        kind = step.get("type")
        if kind not in STEPS:
            raise DescriptionError(f"{field}.type", f"must be one of {', '.join(STEPS)} "
                                                    f"(got {kind!r})")
        label = step.get("point") or step.get("key") or _group_label(step.get("points"))
        field = f"{self.field}.steps[{i}] ({kind} {label})" if isinstance(label, str) else field
        self.step_name = f"{kind} {label}"
        self.model.where = field
        required, optional = STEPS[kind].keys
        check_keys(field, step, required, optional | COMMON_KEYS)
        if "point" in step:
            self.check_new_point(f"{field}.point", step["point"])
        try:
            STEPS[kind].place(self, field, step)
        except ValueError as exc:      # Model.add: a key defined twice
            raise DescriptionError(f"{field}.columns", str(exc)) from None

    def role(self, formula: str, sym: Sym) -> str:
        """CONSTANT when a quantity depends on the parameters alone (one named cell)."""
        if not sym.shown:
            return ALIAS
        by_key = {q.key: q for q in self.model.quantities}

        def fixed(k: str) -> bool:
            if k in self.symbols:
                return True
            q = by_key.get(k)
            return q is not None and q.role in (ALIAS, CONSTANT) and \
                all(fixed(r) for r in references(q.formula))
        return CONSTANT if all(fixed(k) for k in references(formula)) else COLUMN

    def witness(self, field: str, cols: dict[str, Sym], order: tuple[str, ...]) -> None:
        """A shown column of a loop step: a number exactly where this loop closes."""
        for name in order:
            if cols[name].shown:
                self.model.closes += (cols[name].key,)
                self.model.loop_steps += ((field, self.step_name),)
                return
        raise DescriptionError(f"{field}.columns", f"a loop step must show one of "
                                                   f"{', '.join(order)}")


def _group_label(points: object) -> str | None:
    """A group's points as its label in messages ("D E F"), if they are names."""
    if isinstance(points, list) and points and all(isinstance(p, str) for p in points):
        return " ".join(points)
    return None


def parameter_kinds(origin: str, table: dict, defaults: dict[str, str] | None = None
                    ) -> dict[str, str]:
    """Each parameter's kind: `kind` of its entry, else its default (an older template's symbol
    takes the bundled template's kind), else a length."""
    defaults = defaults or {}
    kinds = {}
    for symbol, entry in table.items():
        field = f"{origin}: parameters.{symbol}"
        if not IDENT.match(symbol) or keyword.iskeyword(symbol):
            raise DescriptionError(field, "a symbol must be letters, digits and _, starting with "
                                          "a letter")
        kind = defaults.get(symbol, LENGTH_KIND)
        kind = entry.get("kind", kind) if isinstance(entry, dict) else kind
        if kind not in KINDS:
            raise DescriptionError(f"{field}.kind", f"must be one of {', '.join(KINDS)} "
                                                    f"(got {kind!r})")
        kinds[symbol] = kind
    return kinds


def compile_mechanism(name: str, data: dict, kinds: dict[str, str], origin: str,
                      grid: tuple[str, str] | None = None) -> Mechanism:
    """The Mechanism a described template builds, checked through (DescriptionError)."""
    c = Compiler(data, kinds, origin)
    model = c.run()
    if grid is not None:
        if c.input_kind != ANGLE_KIND:
            raise DescriptionError(f"{origin}: grid", "a grid sweeps a crank turn; this "
                                                      "mechanism's input is a length")
        param, out = grid
        if param not in kinds:
            raise DescriptionError(f"{origin}: grid.parameter", f"{param!r} is not a parameter")
        group = next((r["field"] for r in c.records if r["type"] == "triad"), None)
        if group is not None:       # a grid cell is one self-contained formula: no row above
            raise DescriptionError(f"{origin}: grid", f"{group} is solved by iterations "
                                                      "continued from row to row, which a "
                                                      "grid's self-contained cells cannot do")
        if out not in {q.key for q in model.of_role(COLUMN)}:
            raise DescriptionError(f"{origin}: grid.output", f"{out!r} is not a shown column")
    return Mechanism(name, dict(c.kinds), c.input_key, c.input_symbol, lambda: model, grid,
                     description=data, input_kind=c.input_kind, lengths=tuple(c.lengths),
                     loads=tuple(c.loads))
