"""The build record, typed: what a workbook holds and where, as the writer records it in the
hidden `linkbook` sheet (sheets.write_meta) and as every reader of a book (verify, info, export,
animate) reads it back.

The JSON keeps one shape (FORMAT_VERSION). `upgrade` turns the record of an older book, which
lacks entries later books write, into today's shape, so that no reader needs a branch for it.
`BuildRecord.from_json` checks the shape: a key it does not know, a key missing or a value of
the wrong type raises KeyError, TypeError or ValueError (a damaged record, or a writer's typo
caught at build). `to_json` gives back exactly what the writer recorded, so the sheet's text is
the same whether it is written from the writer's dict or from the record.
"""
from __future__ import annotations

from dataclasses import MISSING, FrozenInstanceError, dataclass, field, fields, is_dataclass

from .palette import link_label

FORMAT_VERSION = 1
SWEEP_SHEET = "Sweep"       # the sweep's sheet in books that did not record it (sheets.SWEEP)


class DamagedRecord(ValueError):
    """The text is no build record of this format (not a JSON object, another format)."""


# ---------------------------------------------------------------- checking JSON values
def _typed(kinds: tuple, what: str):
    def check(value):
        if not isinstance(value, kinds) or (bool not in kinds and isinstance(value, bool)):
            raise TypeError(f"{what} expected, got {type(value).__name__}")
        return value
    return check


_str = _typed((str,), "a text")
_int = _typed((int,), "a whole number")
_bool = _typed((bool,), "true or false")
_number = _typed((int, float), "a number")      # kept as written: 1.0 stays 1.0 in the JSON
_object = _typed((dict,), "an object")


def _optional(convert):
    return lambda value: None if value is None else convert(value)


def _list(convert):
    def check(value):
        return tuple(convert(v) for v in _typed((list, tuple), "a list")(value))
    return check


def _pair(convert):
    def check(value):
        items = _list(convert)(value)
        if len(items) != 2:
            raise ValueError(f"a pair expected, got {len(items)} items")
        return items
    return check


def _map(convert):
    return lambda value: {_str(k): convert(v) for k, v in _object(value).items()}


def _part(cls):
    return lambda value: cls.from_json(value)


_rows = _pair(_int)           # the first and last row of a block
_cells = _map(_str)           # key → cell address or column letter


def _entry(convert, default=MISSING, written_when_none=False):
    """A field read from the JSON key of its name through `convert`. With a default, the key
    may be missing; a field whose value is None is left out of the JSON unless
    `written_when_none`."""
    meta = {"convert": convert, "written_when_none": written_when_none}
    return field(metadata=meta) if default is MISSING else field(default=default, metadata=meta)


class Part:
    """One object of the record: its dataclass fields are its JSON keys.

    A part is a value, as a frozen dataclass is: made from its fields as arguments (in order or
    by name, the defaulted ones optional), equal to a part of its class with equal fields,
    hashed and shown by them (`Sweep(sheet='Sweep', ...)`), never changed (FrozenInstanceError).
    A frozen dataclass writes and compiles these six methods for each of its classes whenever
    the module is imported, which every command does; written once here, they cost nothing per
    part, and each part is a dataclass only for its fields (`_frozen`)."""

    def __init__(self, *args, **kwargs):
        known = fields(self)
        if len(args) > len(known):
            raise TypeError(f"{type(self).__name__}() takes {len(known)} arguments "
                            f"({len(args)} given)")
        given = dict(zip((f.name for f in known), args))
        for name, value in kwargs.items():
            if name in given or name not in {f.name for f in known}:
                raise TypeError(f"{type(self).__name__}() got "
                                f"{'more than one' if name in given else 'an unexpected'} "
                                f"argument {name!r}")
            given[name] = value
        for f in known:
            if f.name not in given:
                if f.default is MISSING:
                    raise TypeError(f"{type(self).__name__}() missing argument {f.name!r}")
                given[f.name] = f.default
            object.__setattr__(self, f.name, given[f.name])

    def _values(self) -> tuple:
        return tuple(getattr(self, f.name) for f in fields(self))

    def __eq__(self, other):
        if other.__class__ is not self.__class__:
            return NotImplemented
        return self._values() == other._values()

    def __hash__(self):
        return hash(self._values())

    def __repr__(self):
        shown = ", ".join(f"{f.name}={getattr(self, f.name)!r}" for f in fields(self))
        return f"{type(self).__qualname__}({shown})"

    def __setattr__(self, name, value):
        raise FrozenInstanceError(f"cannot assign to field {name!r}")

    def __delattr__(self, name):
        raise FrozenInstanceError(f"cannot delete field {name!r}")

    @classmethod
    def from_json(cls, data):
        data = _object(data)
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise KeyError(f"{cls.__name__}: unknown key {unknown[0]!r}")
        values = {}
        for f in fields(cls):
            if f.name in data:
                values[f.name] = f.metadata["convert"](data[f.name])
            elif f.default is MISSING:
                raise KeyError(f.name)
        return cls(**values)

    def to_json(self) -> dict:
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is not None or f.metadata["written_when_none"]:
                out[f.name] = _json(value)
        return out


def _frozen(cls):
    """A part's class: a dataclass for its fields (fields(), replace()); its methods are Part's."""
    return dataclass(init=False, repr=False, eq=False)(cls)


def _json(value):
    if is_dataclass(value):
        return value.to_json()
    if isinstance(value, dict):
        return {k: _json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    return value


# ---------------------------------------------------------------- the parts
@_frozen
class Input(Part):
    """A named input cell on the Mechanism sheet: a length, an angle, a branch, a rate. A
    designed parameter's row (`designed`) holds a link to its named cell on the Synthesis
    sheet: a formula, not an input; its value is the synthesis's."""
    cell: str = _entry(_str)
    kind: str = _entry(_str)
    name: str = _entry(_str)
    designed: bool | None = _entry(_optional(_bool), None)


@_frozen
class Constant(Part):
    """A derived constant's cell (a time ratio, an angle the description computes once)."""
    cell: str = _entry(_str)
    name: str = _entry(_str)
    unit: str = _entry(_str)


@_frozen
class SummaryCell(Part):
    """A cell of the geometry summary: a number, a number or a dash, or a text."""
    cell: str = _entry(_str)
    kind: str = _entry(_str)
    unit: str = _entry(_str, "")


@_frozen
class Sweep(Part):
    """The sweep table: one row per input value, one column letter per quantity key."""
    sheet: str = _entry(_str)
    rows: tuple[int, int] = _entry(_rows)
    columns: dict[str, str] = _entry(_cells)

    def cells(self, key: str) -> list[str]:
        """The cells of column `key`, top to bottom."""
        from .xlsx import column_cells
        return column_cells(self.columns[key], self.rows[0], self.rows[1])


@_frozen
class Motion(Part):
    """The Motion sheet: the current position's row, then one row per sweep row."""
    sheet: str = _entry(_str)
    rows: tuple[int, int] = _entry(_rows)
    current_row: int = _entry(_int)
    columns: dict[str, str] = _entry(_cells)


@_frozen
class Forces(Motion):
    """The Forces sheet: laid out as the Motion sheet, with the summary of the sweep under it
    (its cells; the coefficient of speed fluctuation is an input among them) and, for a crank,
    the column of the work of the driving torque above its mean."""
    summary: dict[str, SummaryCell] = _entry(_map(_part(SummaryCell)))
    work: str | None = _entry(_optional(_str), None)


@_frozen
class DrawnLink(Part):
    """A link of the drawing: its joints' rows of the joints table (x, y in DRAWING_COLUMNS)."""
    joints: tuple[str, ...] = _entry(_list(_str))
    rows: tuple[int, int] = _entry(_rows)
    label: str = _entry(_str)
    ground: bool | None = _entry(_optional(_bool), None)
    kind: str | None = _entry(_optional(_str), None)    # a slider's guide, slot or block


@_frozen
class Position(Part):
    """The current position block: the input cell, a cell per quantity, the joints table, the
    drawing's links and, with motion, the velocity cells of the traced point."""
    sheet: str = _entry(_str)
    input_cell: str = _entry(_str)
    input_name: str = _entry(_str)
    cells: dict[str, str] = _entry(_cells)
    joints: dict[str, tuple[str, str]] = _entry(_map(_pair(_str)))
    drawing: tuple[DrawnLink, ...] = _entry(_list(_part(DrawnLink)))
    chart_anchor: str = _entry(_str)
    traced: str | None = _entry(_optional(_str), None, written_when_none=True)
    motion_cells: dict[str, str] | None = _entry(_optional(_cells), None)


@_frozen
class NumbersOnly(Part):
    """A numbers-only copy (what MIN and MAX read): of a sweep column, or of one axis of the
    joints table (None where a row holds no joint)."""
    sheet: str = _entry(_str)
    column: str = _entry(_str)
    rows: tuple[int, int] = _entry(_rows)
    sweep: str | None = _entry(_optional(_str), None)
    joints: tuple[str | None, ...] | None = _entry(_optional(_list(_optional(_str))), None)
    axis: int | None = _entry(_optional(_int), None)


@_frozen
class GridTable(Part):
    """The Grid sheet (one column per value of the adjustment `param`, the quantity `key` in
    its cells, the stroke in `stroke_row`) or the Stroke sweep (the same columns sampled more
    finely; a grid that samples finely enough is its own stroke sweep and recorded twice)."""
    sheet: str = _entry(_str)
    rows: tuple[int, int] = _entry(_rows)
    columns: tuple[str, ...] = _entry(_list(_str))
    param_row: int = _entry(_int)
    key: str | None = _entry(_optional(_str), None)
    param: str | None = _entry(_optional(_str), None)
    stroke_row: int | None = _entry(_optional(_int), None)
    stroke_step: float | None = _entry(_optional(_number), None)   # the template's, in degrees


@_frozen
class Extent(Part):
    """What a frame must hold: sweep columns on each axis, and the joints if `position`."""
    x: tuple[str, ...] = _entry(_list(_str))
    y: tuple[str, ...] = _entry(_list(_str))
    position: bool = _entry(_bool)


@_frozen
class Series(Part):
    """A mapped column pair of a frame: the drawing's links, or a sweep path (x, y keys)."""
    kind: str = _entry(_str)
    title: str = _entry(_str)
    columns: tuple[str, str] = _entry(_pair(_str))
    rows: tuple[int, int] = _entry(_rows)
    mapped_rows: tuple[int, int] = _entry(_rows)
    source: tuple[str, str] = _entry(_pair(_str))
    sheet: str | None = _entry(_optional(_str), None)
    x: str | None = _entry(_optional(_str), None)
    y: str | None = _entry(_optional(_str), None)


@_frozen
class Bar(Part):
    """The scale bar's cells."""
    columns: tuple[str, ...] = _entry(_list(_str))
    rows: tuple[int, ...] = _entry(_list(_int))


@_frozen
class Frame(Part):
    """An equal-scale frame: the drawing's (no `chart`) or that of sweep chart `chart`."""
    cells: dict[str, str] = _entry(_cells)     # xmin … ymax, cx, cy, need, decade, square, label
    extent: Extent = _entry(_part(Extent))
    series: tuple[Series, ...] = _entry(_list(_part(Series)))
    bar: Bar = _entry(_part(Bar))
    chart: int | None = _entry(_optional(_int), None)


@_frozen
class Frames(Part):
    """The equal-scale frames of the drawing and of the sweep charts, on their sheet."""
    sheet: str = _entry(_str)
    frames: tuple[Frame, ...] = _entry(_list(_part(Frame)))


@_frozen
class Synthesis(Part):
    """The Synthesis sheet (book/synthesis.py): the task as built (`task`: kind, f, spacing,
    points, ground, designs, output), its input cells by key, every result's cell by key, the
    precision points' columns, the structural error's columns and the drawing's cells."""
    sheet: str = _entry(_str)
    task: dict = _entry(_object)
    inputs: dict[str, str] = _entry(_cells)
    cells: dict[str, str] = _entry(_cells)
    points: dict[str, tuple[str, ...]] = _entry(_map(_list(_str)))
    error: dict[str, tuple[str, ...]] = _entry(_map(_list(_str)))
    # the designed linkage at each precision position (book/synthesis_drawing.py): the frame's
    # cells, the scale bar, and per position its legend, θ2, joints, their cells and mapped cells
    drawing: dict | None = _entry(_optional(_object), None)


@_frozen
class ControlSpec(Part):
    """A form control (scroll bar, spin button) linked to `cell`, counting in whole numbers."""
    kind: str = _entry(_str)
    cell: str = _entry(_str)
    min: int = _entry(_int)
    max: int = _entry(_int)
    inc: int = _entry(_int)
    page: int = _entry(_int)
    value: int = _entry(_int)
    anchor: tuple[int, ...] = _entry(_list(_int))


@_frozen
class BuildRecord(Part):
    """What was built (template, mechanism and its description) and where each quantity
    lives in the book."""
    format: int = _entry(_int)
    linkbook: str = _entry(_str)
    template: str = _entry(_str)
    mechanism: str = _entry(_str)
    title: str = _entry(_str)
    length_unit: str = _entry(_str)
    input: str = _entry(_str)
    inputs: dict[str, Input] = _entry(_map(_part(Input)))
    constants: dict[str, Constant] = _entry(_map(_part(Constant)))
    position: Position = _entry(_part(Position))
    sweep: Sweep = _entry(_part(Sweep))
    numbers_only: tuple[NumbersOnly, ...] = _entry(_list(_part(NumbersOnly)))
    summary: dict[str, SummaryCell] = _entry(_map(_part(SummaryCell)))
    controls: dict[str, tuple[ControlSpec, ...]] = _entry(_map(_list(_part(ControlSpec))))
    description: dict | None = _entry(_optional(_object), None)   # the mechanism language's
    motion: Motion | None = _entry(_optional(_part(Motion)), None)
    forces: Forces | None = _entry(_optional(_part(Forces)), None)
    grid: GridTable | None = _entry(_optional(_part(GridTable)), None)
    stroke: GridTable | None = _entry(_optional(_part(GridTable)), None)
    frames: Frames | None = _entry(_optional(_part(Frames)), None)
    synthesis: Synthesis | None = _entry(_optional(_part(Synthesis)), None)

    @classmethod
    def from_json(cls, data) -> "BuildRecord":
        """The record of `data` (any format-1 book's JSON, upgraded to today's shape).
        DamagedRecord when `data` is not a record of this format at all."""
        if not isinstance(data, dict) or data.get("format") != FORMAT_VERSION:
            raise DamagedRecord(f"not the JSON object of format {FORMAT_VERSION} linkbook writes")
        return super().from_json(upgrade(data))

    def kinds(self) -> dict[str, str]:
        """Each input symbol's kind (length, offset, angle, branch, rate)."""
        return {symbol: i.kind for symbol, i in self.inputs.items()}

    def sheets(self) -> set[str]:
        """Every sheet the record names."""
        parts = [self.position, self.sweep, self.motion, self.forces, self.grid, self.stroke,
                 self.frames, self.synthesis,
                 *self.numbers_only]
        named = {p.sheet for p in parts if p is not None}
        if self.frames is not None:
            named |= {s.sheet for f in self.frames.frames for s in f.series if s.sheet}
        return named


# ---------------------------------------------------------------- older books
def upgrade(data: dict) -> dict:
    """A format-1 record in today's shape: the entries older books lack, filled in as those
    books were laid out (their length unit mm, their sweep on the Sweep sheet, no constants, no
    summary, no numbers-only copies, no controls; their drawn links numbered from 1). A record
    already in today's shape comes back equal."""
    out = dict(data)
    out.setdefault("title", out.get("template", ""))
    out.setdefault("length_unit", "mm")
    out.setdefault("input", "input")
    for key, empty in (("constants", {}), ("summary", {}), ("numbers_only", []),
                       ("controls", {})):
        out.setdefault(key, empty)
    sweep = out.get("sweep")
    if isinstance(sweep, dict) and "sheet" not in sweep:
        out["sweep"] = {**sweep, "sheet": SWEEP_SHEET}
    position = out.get("position")
    if isinstance(position, dict) and isinstance(position.get("drawing"), list):
        drawing = [_labelled(link, i) for i, link in enumerate(position["drawing"], start=1)]
        out["position"] = {**position, "drawing": drawing}
    return out


def _labelled(link, i: int):
    """A drawn link with its legend's name (palette.link_label: books built before labels
    number their links from 1)."""
    if not isinstance(link, dict) or "label" in link or not isinstance(link.get("joints"), list):
        return link
    return {**link, "label": link_label(link, i)}
