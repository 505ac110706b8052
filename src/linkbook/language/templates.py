"""Templates: a mechanism's dimensions, sweep and presentation as data (templates/*.toml).

Every value a user gives — in a TOML file or with --set/--step/--branch — is checked here, and a
bad one raises InputError naming the field, before any file is touched.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace
from pathlib import Path

from ..base.xlsx import excel_name_problem
from .domain import (BRANCH_WORDS, LENGTH_UNITS, InputError, check_input,
                     check_lengths_together, check_value, check_written_lengths, parse_number)
from .bundled import TEMPLATE_DIR, bundled, bundled_template_data
from .compiler import DescriptionError, compile_mechanism, parameter_kinds
from .expressions import always_an_error, value_of
from .fields import check_nesting
from .synthesis import DyadTask, FunctionTask, design, fitted_to, task_of
from .mechanisms import (ANGLE_KIND, LENGTH_KIND, LOAD_UNITS, MOTION_SYMBOLS, OFFSET_KIND,
                         RATE_KIND, Mechanism, typed_unit)

EXCEL_MAX_ROWS = 1_048_576
EXCEL_MAX_COLUMNS = 16_384


# What a message calls each override: the command line's flags, or the Python API's arguments
# (linkbook.build(sets=..., step=..., branch=..., unit=...)).
FLAGS = {"set": "--set", "step": "--step", "branch": "--branch", "unit": "--unit", "output": "-o"}
ARGUMENTS = {"set": "sets", "step": "step", "branch": "branch", "unit": "unit",
             "output": "output"}


@dataclass(frozen=True)
class Parameter:
    """One input of a template: its symbol, kind, unit, named cell and value."""
    symbol: str
    kind: str
    label: str
    unit: str
    name: str        # the workbook-scoped defined name of its cell
    value: float
    # the template field whose formula the cell holds ("synthesis.designs.crank"): a designed
    # parameter's named cell is a formula on the Synthesis sheet, not an input; "" for an input
    designed_by: str = ""


@dataclass(frozen=True)
class Sweep:
    """The input's sweep: from start to stop by step."""
    start: float
    stop: float
    step: float

    def angles(self) -> list[float]:
        """start, start + step, … and always stop itself: a step that does not divide the
        range ends with one shorter step, so that a full turn closes (the coupler curve too)."""
        count = int(math.floor((self.stop - self.start) / self.step + 1e-9)) + 1
        angles = [round(self.start + i * self.step, 10) for i in range(count)]
        if angles[-1] < self.stop - 1e-9 * self.step:
            angles.append(round(self.stop, 10))
        return angles


@dataclass(frozen=True)
class Template:
    """A template read and checked: its mechanism, parameters, sweep and layout."""
    name: str
    title: str
    source: str
    description: str
    mechanism: Mechanism
    length_unit: str
    parameters: tuple[Parameter, ...]
    sweep: Sweep
    position: float                      # the current-position input angle, degrees
    grid_values: tuple[float, ...] = ()  # values of mechanism.grid's parameter across the grid
    stroke_step: float = 1.0             # fine sweep under the grid, degrees
    synthesis: FunctionTask | DyadTask | None = None   # the task that designs some parameters

    def values(self) -> dict[str, float]:
        return {p.symbol: p.value for p in self.parameters}

    def known_values(self) -> dict[str, float]:
        """values() without a designed parameter the task leaves undesigned (NaN): the
        template's checks skip what reads it; the book shows #N/A there."""
        return {p.symbol: p.value for p in self.parameters
                if not (p.designed_by and math.isnan(p.value))}

    def parameter(self, symbol: str) -> Parameter:
        for p in self.parameters:
            if p.symbol == symbol:
                return p
        raise KeyError(symbol)


# ---------------------------------------------------------------- names
def default_name(symbol: str) -> str:
    """a2 -> a_2, gamma3 -> gamma_3: never a cell-like name such as A2 or B3; a symbol that is
    still one (c, r: columns and rows in R1C1) gets a prefix: p_c."""
    name = re.sub(r"^([A-Za-z]+)(\d+)$", r"\1_\2", symbol)
    return f"p_{name}" if excel_name_problem(name) else name


# ---------------------------------------------------------------- values
def parse_list(field: str, kind: str, text: object) -> tuple[float, ...]:
    """'20,50,100' (command line) or [20, 50, 100] (TOML) -> checked values."""
    items = text if isinstance(text, list) else str(text).split(",")
    if not items or any(isinstance(i, str) and not i.strip() for i in items):
        raise InputError(field, f"must be a comma-separated list of numbers (got {text!r})")
    return tuple(check_value(field, kind, item) for item in items)


# ---------------------------------------------------------------- loading
def find(name_or_path: str) -> Path:
    path = Path(name_or_path)
    # a folder or a suffix says a file is meant (`../own/x.tml`), never a bundled name
    if path.suffix or path.exists() or len(path.parts) > 1:
        if not path.is_file():
            raise InputError("template", f"no such file {name_or_path!r}{_suffix_hint(path)}"
                                         f"{_bundled_hint(path)}")
        return path
    candidate = TEMPLATE_DIR / f"{name_or_path}.toml"
    if candidate.is_file():
        return candidate
    import difflib
    names = [p.stem for p in bundled()]
    hint = difflib.get_close_matches(name_or_path, names, n=1)
    more = f"; did you mean {hint[0]!r}?" if hint else f"; known: {', '.join(names)}"
    raise InputError("template", f"unknown template {name_or_path!r}{more}")


def _suffix_hint(path: Path) -> str:
    if path.suffix.lower() in ("", ".toml"):
        return ""
    return f" (a template is a .toml file, not {path.suffix})"


def _bundled_hint(path: Path) -> str:
    """A missing file named like a bundled template: the name alone builds that one."""
    if path.suffix == ".toml" and (TEMPLATE_DIR / f"{path.stem}.toml").is_file():
        return (f"; the bundled template is `{path.stem}` (no .toml), and `linkbook new "
                f"{path.stem} {path.name}` copies it here to edit")
    return ""


def copy_bundled(name: str, out: Path) -> Path:
    """A bundled template copied to `out`, a new .toml file (never over an existing one)."""
    source = TEMPLATE_DIR / f"{name}.toml"
    if not source.is_file():
        find(name)                  # the unknown-template error, with its suggestion
    if out.suffix != ".toml":
        raise InputError("new", f"the copy must be a .toml file (got {str(out)!r})")
    if not out.parent.is_dir():
        raise InputError("new", f"folder {str(out.parent)!r} does not exist")
    try:
        with open(out, "x", encoding="utf-8") as f:
            f.write(source.read_text(encoding="utf-8"))
    except FileExistsError:
        raise InputError(str(out), "exists already; linkbook new never overwrites a "
                                   "file") from None
    except OSError as exc:
        raise InputError(str(out), f"cannot be written ({exc.strerror or exc})") from None
    return out


def load(name_or_path: str) -> Template:
    import tomllib
    path = find(name_or_path)
    try:
        # utf-8-sig: Windows editors start a UTF-8 file with a byte-order mark
        data = tomllib.loads(path.read_text(encoding="utf-8-sig"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(path.name, f"is not valid TOML ({exc})") from None
    except RecursionError:
        raise InputError(path.name, "nests tables or arrays too deeply to be read") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(path.name, f"cannot be read ({exc})") from None
    return from_data(path.stem, data, origin=path.name)


def _need(data: dict, key: str, origin: str, kind: type | tuple = str):
    if key not in data:
        raise InputError(f"{origin}: {key}", "is missing")
    value = data[key]
    if not isinstance(value, kind) or isinstance(value, bool) and kind is not bool:
        raise InputError(f"{origin}: {key}", f"has the wrong type (got {value!r})")
    if isinstance(value, str):
        check_text(f"{origin}: {key}", value)
    return value


def _optional_text(data: dict, key: str, origin: str) -> str:
    return _need(data, key, origin) if key in data else ""


CELL_TEXT_MAX = 32_767          # characters in one Excel cell


def check_text(field: str, text: str) -> str:
    """Text that goes into a cell: no character a workbook cannot hold (control characters,
    U+FFFE, U+FFFF, surrogates), and at most a quarter of what a cell holds (labels share cells
    with units and notes)."""
    from ..base.xlsx import NOT_IN_XML
    bad = NOT_IN_XML.search(text)
    if bad:
        kind = "control character" if bad.group() < " " else "character"
        raise InputError(field, f"contains the {kind} U+{ord(bad.group()):04X}, "
                                "which a workbook cannot hold")
    if len(text) > CELL_TEXT_MAX // 4:
        raise InputError(field, f"is {len(text):,} characters long (at most "
                                f"{CELL_TEXT_MAX // 4:,})")
    return text


def from_data(name: str, data: dict, origin: str = "template") -> Template:
    try:
        check_nesting("", data)
    except DescriptionError as exc:
        raise InputError(f"{origin}: {exc.field}", exc.message) from None
    check_schema(data, origin)
    mech = _mechanism(name, data, origin)
    length_unit = check_length_unit(f"{origin}: length_unit", _need(data, "length_unit", origin))
    table = _need(data, "parameters", origin, dict)
    unknown = [s for s in table if s not in mech.parameters]
    if unknown:
        raise InputError(f"{origin}: parameters.{unknown[0]}",
                         f"is not a parameter of {mech.name}; it has {', '.join(mech.parameters)}")
    task = task_of(data, mech.parameters, origin)
    if task is not None:
        task = fitted_to(task, mech.description or {}, origin)
    designed = task.designed() if task else {}
    params = []
    for symbol, kind in mech.parameters.items():
        field = f"{origin}: parameters.{symbol}"
        if symbol not in table and kind != RATE_KIND:
            raise InputError(field, "is missing")
        entry = table.get(symbol) or motion_default(mech, symbol, length_unit)
        if not isinstance(entry, dict):
            raise InputError(field, f"must be a table with label, unit, value (got {entry!r})")
        label = _need(entry, "label", field)
        typed = _need(entry, "unit", field)
        unit = typed_unit(typed)
        want = parameter_unit(mech, symbol, kind, length_unit)
        if unit != want:
            raise InputError(f"{field}.unit", f"must be {want} for a{'n' if kind[0] in 'aio' else ''} "
                                              f"{kind} parameter in a book of {length_unit} "
                                              f"(got {typed!r})")
        excel_name = entry.get("name", default_name(symbol))
        problem = (excel_name_problem(excel_name) if isinstance(excel_name, str)
                   else "must be text")
        if problem:
            raise InputError(f"{field}.name", f"{excel_name!r} {problem}")
        if symbol in designed:
            if "value" in entry:
                raise InputError(f"{field}.value", f"{symbol} is designed by "
                                                   f"synthesis.designs.{designed[symbol]}; "
                                                   "leave its value out")
            params.append(Parameter(symbol, kind, label, unit, excel_name, math.nan,
                                    f"synthesis.designs.{designed[symbol]}"))
            continue
        if "value" not in entry:
            raise InputError(f"{field}.value", "is missing")
        value = (parse_list(f"{field}.value", kind, entry["value"])[0]
                 if isinstance(entry["value"], list) else
                 check_value(f"{field}.value", kind, entry["value"]))
        params.append(Parameter(symbol, kind, label, unit, excel_name, value))
    _check_unique_names(params, origin)
    _check_own_names(params, mech, origin)
    sweep_data = _need(data, "sweep", origin, dict)
    sweep = Sweep(*(parse_number(f"{origin}: sweep.{k}", _need(sweep_data, k, f"{origin}: sweep",
                                                               (int, float)))
                    for k in ("start", "stop", "step")))
    position = parse_number(f"{origin}: sweep.position", sweep_data.get("position", sweep.start))
    grid_values: tuple[float, ...] = ()
    stroke_step = 1.0
    if mech.grid:
        grid_param = mech.grid[0]
        grid = _need(data, "grid", origin, dict)
        allowed = {"values", "stroke_step", "parameter", "output"}
        for k in grid:
            if k not in allowed:
                raise InputError(f"{origin}: grid.{k}", f"is not a key here; known: "
                                                        f"{', '.join(sorted(allowed))}")
        grid_values = parse_list(f"{origin}: grid.values", mech.parameters[grid_param],
                                 _need(grid, "values", f"{origin}: grid", list))
        stroke_step = parse_number(f"{origin}: grid.stroke_step", grid.get("stroke_step", 1.0))
    template = Template(
        name=name, title=_need(data, "title", origin), source=_optional_text(data, "source", origin),
        description=_optional_text(data, "description", origin), mechanism=mech, length_unit=length_unit,
        parameters=tuple(params), sweep=sweep, position=position, grid_values=grid_values,
        stroke_step=stroke_step, synthesis=task)
    template = with_design(template)
    check_sweep(template, origin)
    return template


def with_design(t: Template) -> Template:
    """The template with its designed parameters' values designed anew from its task and its
    ground length (NaN where there is no usable design)."""
    if t.synthesis is None:
        return t
    values = design(t.synthesis, t.values())
    roles = t.synthesis.designed()
    return replace(t, parameters=tuple(
        replace(p, value=values[roles[p.symbol]]) if p.symbol in roles else p
        for p in t.parameters))


def check_schema(data: dict, origin: str) -> None:
    """The template against the schema of what a template may contain, before the semantic
    checks: an unknown key, a wrong type or a missing key, one line naming the field."""
    from .schema import problem
    found = problem(data)
    if found:
        field, message = found
        raise InputError(f"{origin}: {field}" if field else origin, message)


def check_length_unit(field: str, unit: object) -> str:
    if unit not in LENGTH_UNITS:
        raise InputError(field, f"must be one of {', '.join(LENGTH_UNITS)} (got {unit!r})")
    return unit


def parameter_unit(mech: Mechanism, symbol: str, kind: str, length_unit: str) -> str:
    """The one unit a parameter of this kind may have in a book of `length_unit`."""
    if kind in (LENGTH_KIND, OFFSET_KIND):
        return length_unit
    if kind == ANGLE_KIND:
        return "deg"
    if kind == RATE_KIND:
        return motion_default(mech, symbol, length_unit)["unit"]
    return LOAD_UNITS.get(kind, "-")


def with_unit(t: "Template", unit: str, flag: str = FLAGS["unit"]) -> "Template":
    """The same mechanism with lengths in `unit`: every length and offset parameter, a linear
    actuator's sweep, position and rates, and length grid values converted. `flag`: what the
    messages call the unit's setting."""
    from .dimensions import unconvertible
    check_length_unit(flag, unit)
    if unit == t.length_unit:
        return t
    found = unconvertible(t.mechanism, t.mechanism.build())
    if found:
        field, why = found
        raise InputError(flag, f"{field}: {why}")
    factor = LENGTH_UNITS[t.length_unit] / LENGTH_UNITS[unit]
    linear_rates = set(MOTION_SYMBOLS[LENGTH_KIND])
    params = []
    for p in t.parameters:
        converts = p.kind in (LENGTH_KIND, OFFSET_KIND) or \
            (p.kind == RATE_KIND and p.symbol in linear_rates)
        params.append(replace(p, value=p.value * factor if converts else p.value,
                              unit=parameter_unit(t.mechanism, p.symbol, p.kind, unit)))
    sweep, position = t.sweep, t.position
    if not t.mechanism.input_is_angle:
        sweep = Sweep(sweep.start * factor, sweep.stop * factor, sweep.step * factor)
        position *= factor
    grid_values = t.grid_values
    if t.mechanism.grid and t.mechanism.parameters[t.mechanism.grid[0]] in (LENGTH_KIND,
                                                                               OFFSET_KIND):
        grid_values = tuple(v * factor for v in grid_values)
    task = t.synthesis.in_unit(factor) if t.synthesis is not None else None
    out = with_design(replace(t, parameters=tuple(params), sweep=sweep, position=position,
                              grid_values=grid_values, length_unit=unit, synthesis=task))
    check_sweep(out)
    return out


def motion_default(mech: Mechanism, symbol: str, length_unit: str) -> dict:
    """The input's speed and acceleration where a template does not give them: a crank at
    10 rad/s (95.5 rpm), an actuator at 100 length units per second, neither accelerating."""
    speed, _ = MOTION_SYMBOLS[mech.input_kind]
    if mech.input_is_angle:
        label, unit, value = (("crank angular velocity", "rad/s", 10.0) if symbol == speed else
                              ("crank angular acceleration", "rad/s²", 0.0))
    else:
        label, unit, value = (("actuator velocity", f"{length_unit}/s", 100.0)
                              if symbol == speed else
                              ("actuator acceleration", f"{length_unit}/s²", 0.0))
    return {"label": label, "unit": unit, "value": value, "name": symbol}


def _mechanism(name: str, data: dict, origin: str) -> Mechanism:
    """The mechanism the template describes (docs/language.md). The older form names a bundled
    template's mechanism (`mechanism = "fourbar"`): its description and parameter kinds."""
    raw = data.get("mechanism")
    table = _need(data, "parameters", origin, dict)
    kinds: dict[str, str] = {}
    grid_keys = None
    grid = data.get("grid")
    if isinstance(raw, str):
        bundled_data = bundled_template_data(raw)
        if bundled_data is None:
            known = ", ".join(p.stem for p in bundled())
            raise InputError(f"{origin}: mechanism", f"unknown mechanism {raw!r}; known: {known}")
        raw = bundled_data["mechanism"]
        kinds = {s: e.get("kind", LENGTH_KIND) for s, e in bundled_data["parameters"].items()}
        if "grid" in bundled_data:
            grid_keys = (bundled_data["grid"]["parameter"], bundled_data["grid"]["output"])
    elif not isinstance(raw, dict):
        raise InputError(f"{origin}: mechanism", "is missing: a [mechanism] table "
                                                 "(docs/language.md) or a bundled name")
    if isinstance(grid, dict) and ("parameter" in grid or "output" in grid):
        grid_keys = (_need(grid, "parameter", f"{origin}: grid"),
                     _need(grid, "output", f"{origin}: grid"))
    try:
        return compile_mechanism(name, raw, parameter_kinds(origin, table, kinds), origin,
                                 grid_keys)
    except DescriptionError as exc:
        raise InputError(exc.field, exc.message) from None


def _check_unique_names(params: list[Parameter], origin: str) -> None:
    seen: dict[str, str] = {}
    for p in params:
        other = seen.setdefault(p.name.upper(), p.symbol)
        if other != p.symbol:
            raise InputError(f"{origin}: parameters.{p.symbol}.name",
                             f"{p.name!r} is already the name of {other}")


def _check_own_names(params: list[Parameter], mech: Mechanism, origin: str) -> None:
    """No parameter named as a cell the book names itself: two cells of one name, or a
    placeholder standing for two cells, leave formulas reading the wrong one."""
    own = {name.upper(): (name, what) for name, what in mech.book_names().items()}
    for p in params:
        for field, name in ((f"parameters.{p.symbol}", p.symbol),
                            (f"parameters.{p.symbol}.name", p.name)):
            if name.upper() in own:
                taken, what = own[name.upper()]
                raise InputError(f"{origin}: {field}", f"{name!r} is the book's own name "
                                                       f"{taken!r} ({what}); choose another")


def check_step_lengths(t: Template) -> None:
    """Every length a step takes (a side, a rod, a crank), evaluated with the book's values,
    must be positive: the loop cannot be assembled with a zero or negative one, and a book
    built so would be #N/A all through. A length of the swept input is checked by the sweep."""
    values = t.known_values()
    for field, raw in t.mechanism.lengths:
        value = value_of(raw, values)
        if value is None or value > 0:
            continue
        shown = "not a number" if math.isnan(value) else f"{value:g} {t.length_unit}"
        given = "" if not isinstance(raw, str) else f"{raw!r} = "
        raise InputError(field, f"{given}{shown} with these parameters; a length must be "
                                "positive")


def check_loads(t: Template) -> None:
    """No mass, inertia, load or gravity an error on every row with the book's values (NA(),
    1/0): a book of forces that are all errors, which the reference reads as #N/A where the
    book shows #DIV/0!, or as numbers where the loads were meant to be."""
    values = t.known_values()
    for field, raw in t.mechanism.loads:
        if always_an_error(raw, values):
            raise InputError(field, f"{raw!r} is an error (#N/A, #DIV/0!, #NUM!) on every row "
                                    "with these parameters; it must be a number")


def check_sweep(t: Template, origin: str = "", step_field: str = "sweep.step") -> None:
    """Positive step, start < stop, the sweep and the current position within the inputs a book
    supports, and tables inside Excel's limits — before any work; and lengths that fit one book
    (check_lengths_together, with the lengths the description writes as numbers), each step's
    length positive (check_step_lengths), no load an error throughout (check_loads). Called after
    every change to a template. `origin` names the template file, `step_field` where the step
    came from (the file's sweep.step, --step)."""
    values = t.known_values()
    if t.mechanism.grid:
        values = {**values, **{f"{t.mechanism.grid[0]}[{i}]": v
                               for i, v in enumerate(t.grid_values)}}
    kinds = {p.symbol: p.kind for p in t.parameters}
    if t.mechanism.grid:
        kinds.update({f"{t.mechanism.grid[0]}[{i}]": kinds[t.mechanism.grid[0]]
                      for i in range(len(t.grid_values))})
    where = f"{origin}: " if origin else ""
    written = check_written_lengths(t.mechanism.description or {}, where)
    check_lengths_together(values, kinds, f"{where}parameters.", written)
    check_step_lengths(t)
    check_loads(t)
    s = t.sweep
    for field, value in (("sweep.start", s.start), ("sweep.stop", s.stop),
                         ("sweep.position", t.position)):
        check_input(f"{where}{field}", value, t.mechanism.input_is_angle)
    unit = "degrees" if t.mechanism.input_is_angle else t.length_unit
    if s.step <= 0:
        raise InputError(f"{where}{step_field}", f"must be a positive {t.mechanism.input_word} "
                                                 f"in {unit} (got {s.step:g})")
    if not t.mechanism.input_is_angle and s.start <= 0:
        raise InputError(f"{where}sweep.start", f"a linear actuator's length must be positive "
                                                f"(got {s.start:g} {unit})")
    if s.stop <= s.start:
        raise InputError(f"{where}sweep", f"stop must be greater than start (got "
                                          f"{s.start:g}..{s.stop:g})")
    rows = (s.stop - s.start) / s.step + 2
    if rows > EXCEL_MAX_ROWS - 10:
        raise InputError(f"{where}{step_field}", f"{s.step:g} {unit} gives {rows:,.0f} rows; "
                                                 f"Excel allows {EXCEL_MAX_ROWS:,} per sheet")
    if t.mechanism.grid:
        if t.stroke_step <= 0:
            raise InputError(f"{where}grid.stroke_step", f"must be positive (got "
                                                         f"{t.stroke_step:g})")
        if len(t.grid_values) + 1 > EXCEL_MAX_COLUMNS:
            raise InputError(f"{where}grid.values", f"{len(t.grid_values):,} grid columns; "
                                                    f"Excel allows {EXCEL_MAX_COLUMNS:,}")
        fine_rows = 360 / t.stroke_step + 1
        if fine_rows > EXCEL_MAX_ROWS - 10:
            raise InputError(f"{where}grid.stroke_step", f"gives {fine_rows:,.0f} rows; Excel "
                                                         f"allows {EXCEL_MAX_ROWS:,}")


# ---------------------------------------------------------------- command-line overrides
def parse_assignment(text: str, flag: str = FLAGS["set"]) -> tuple[str, str]:
    if not isinstance(text, str):
        raise InputError(flag, f"expects KEY=VALUE texts (got {text!r})")
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise InputError(flag, f"expects KEY=VALUE (got {text!r})")
    return key.strip(), value.strip()


def with_overrides(t: Template, assignments: list[str] = (), step: float | None = None,
                   branch: str | None = None, names: dict[str, str] = FLAGS) -> Template:
    """The template with --set KEY=VALUE, --step and --branch applied and checked; `names`
    says what the messages call them (FLAGS or ARGUMENTS)."""
    values = {p.symbol: p for p in t.parameters}
    grid_values = t.grid_values
    for text in assignments:
        key, raw = parse_assignment(text, names["set"])
        if key not in values:
            import difflib
            # symbols are case-sensitive (I2 is an inertia, a2 a length); A2 means a2
            hint = [s for s in values if s.lower() == key.lower()] or \
                difflib.get_close_matches(key, list(values), n=1)
            more = f"; did you mean {hint[0]}?" if hint else f"; known: {', '.join(values)}"
            raise InputError(f"{names['set']} {key}", f"unknown parameter{more}")
        p = values[key]
        field = f"{names['set']} {key}"
        if p.designed_by:
            raise InputError(field, f"{key} is designed by {p.designed_by}; change the task "
                                    "instead")
        if t.mechanism.grid and key == t.mechanism.grid[0]:
            grid_values = parse_list(field, p.kind, raw)
            values[key] = replace(p, value=grid_values[0])
        else:
            values[key] = replace(p, value=check_value(field, p.kind, raw))
    if branch is not None:
        if "branch" not in values:
            raise InputError(names["branch"], f"{t.name} has no assembly branch to choose")
        if values["branch"].designed_by:
            raise InputError(names["branch"], f"the branch is designed by "
                                              f"{values['branch'].designed_by}")
        if branch not in BRANCH_WORDS:
            raise InputError(names["branch"], f"must be open or crossed (got {branch!r})")
        values["branch"] = replace(values["branch"], value=BRANCH_WORDS[branch])
    sweep = t.sweep
    if step is not None:
        sweep = replace(sweep, step=parse_number(names["step"], step))
    out = with_design(replace(t, parameters=tuple(values[s] for s in values), sweep=sweep,
                              grid_values=grid_values))
    check_sweep(out, step_field=names["step"] if step is not None else "sweep.step")
    return out
