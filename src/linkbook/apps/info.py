"""`linkbook info`: a book's (or a template's) numbers at the terminal.

Every number is the value of one of the book's own cells, as linkbook's engine computes it from
the book's formulas (so a book edited in Excel reports its edited values). Which cells hold what
comes from the build record (sheets.py), never from fixed addresses."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from ..base import sheets as layout
from ..base.record import BuildRecord
from ..base.xlsx import column_letter, coordinate_to_tuple

# Motion columns whose largest magnitude the summary reports: angular velocities and
# accelerations, the sliders' speeds and accelerations, the traced point's speed and acceleration
PEAK_PREFIXES = ("omega_", "alpha_", "v_", "acc_", "vmag_", "amag_")
# Forces summary cells that are no summary: the two points of the chart's mean line, and the
# corners of the polar diagram's square
CHART_POINTS = ("mean_line_", "polar_square_")
WIDTH = 79      # a terminal's 80 columns, the last left free


@dataclass
class Book:
    """A book ready to be read: its cells, its build record and every cell's value."""
    name: str
    wb: object
    record: BuildRecord
    values: dict


def open_book(path: Path) -> Book:
    """A saved book, evaluated by the engine. UnusableFile (one line) when it cannot be read."""
    from ..engine import evaluator as engine
    from ..check.verifier import UnusableFile, read_book
    path = Path(path)
    if not path.is_file():
        raise UnusableFile(f"{path}: no such file")
    wb, record = read_book(path)
    try:
        values = engine.evaluate(wb)
    except engine.EngineError as exc:
        raise UnusableFile(f"{path}: {exc}") from None
    return Book(str(path), wb, record, values)


def built_book(name_or_toml: str) -> Book:
    """A template built in memory (nothing written) and evaluated. InputError for bad input."""
    from ..language import templates
    from ..book.builder import make
    built, values = make(templates.load(name_or_toml))
    return Book(name_or_toml, built.workbook, built.record, values)


def read_record(book: Book, read):
    """read(book), with a build record that does not match the book (a key missing, a cell
    moved) turned into the one line verify gives for it."""
    from ..check.verifier import UnusableFile, record_mismatch
    try:
        return read(book)
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise UnusableFile(record_mismatch(Path(book.name), exc)) from None


def number(value) -> float | None:
    """A cell's value as a finite float, or None (an error, a text such as "—", empty)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value) if math.isfinite(value) else None


def _plain(value):
    """A number as it is; anything else (a text typed over a number, an error) as its text."""
    return value if value is None or number(value) is not None else str(value)


def column_values(book: Book, sheet: str, letter: str, rows) -> list:
    return [book.values.get((sheet, f"{letter}{r}")) for r in range(rows[0], rows[1] + 1)]


def _text(book: Book, sheet: str, cell: str) -> str:
    value = book.values.get((sheet, cell))
    return "" if value is None else str(value)


def _row_of(cell: str) -> int:
    return coordinate_to_tuple(cell)[0]


def _summary_row(book: Book, key: str) -> tuple[str, object, str] | None:
    """(label, value, unit) of summary cell `key` on the Mechanism sheet: the label and unit
    are the texts beside it in the book."""
    info = book.record.summary.get(key)
    if info is None:
        return None
    row = _row_of(info.cell)
    value = book.values.get((layout.MECH, info.cell))
    return _text(book, layout.MECH, f"A{row}"), value, _text(book, layout.MECH, f"D{row}")


def _inputs(book: Book) -> list[dict]:
    """Each input as its row on the Mechanism sheet shows it: quantity, symbol, value, unit."""
    rows = sorted(_row_of(info.cell) for info in book.record.inputs.values())
    return [{"quantity": _text(book, layout.MECH, f"A{row}"),
             "symbol": _text(book, layout.MECH, f"B{row}"),
             "value": _plain(book.values.get((layout.MECH, f"C{row}"))),
             "unit": _text(book, layout.MECH, f"D{row}")} for row in rows]


# a motion or path generator's designed parameters, in the order `info` lists them
DYAD_ROLES = ("crank", "coupler", "rocker", "ground", "xA0", "yA0", "xB0", "yB0", "u", "v",
              "offset", "branch")


def _synthesis(book: Book) -> dict | None:
    """A synthesis book's design as its Synthesis sheet states it: the designed lengths and
    branch, the checks in words, Grashof's class and the largest structural error."""
    syn = book.record.synthesis
    if syn is None:
        return None

    def cell(key: str):
        return _plain(book.values.get((syn.sheet, syn.cells[key])))
    if syn.task["kind"] != "function":          # motion or path generation: three poses
        designs = syn.task["designs"]
        return {"kind": syn.task["kind"], "unit": book.record.length_unit,
                "designed": {f"{role} {designs[role]}": cell(f"designed_{role}")
                             for role in DYAD_ROLES if role in designs},
                "system": f"crank's {cell('c_system')}, rocker's {cell('r_system')}",
                "lengths": cell("short"), "branch": cell("defect"),
                "grashof": cell("grashof"), "largest_miss": cell("largest_miss"),
                "largest_angle_miss": cell("largest_angle_miss")}
    return {"f": syn.task["f"], "points": syn.task["points"], "spacing": syn.task["spacing"],
            "designed": {f"{role} {syn.task['designs'][role]}": cell(f"designed_{role}")
                         for role in ("crank", "coupler", "rocker", "branch")},
            "system": cell("system"), "lengths": cell("lengths"), "branch": cell("defect"),
            "grashof": cell("grashof"), "largest_error": cell("largest_error"),
            "largest_error_x": cell("largest_error_x")}


def _numbered(book: Book, base: str, suffix: str = ""):
    """Summary keys of the 1st, 2nd, … transmission angle or four-bar loop (summary_prefix)."""
    i = 1
    while (key := layout.summary_prefix(base, i) + suffix) in book.record.summary:
        yield key
        i += 1


def _loops(book: Book) -> list[dict]:
    loops = []
    for key in _numbered(book, "grashof"):
        label, value, _ = _summary_row(book, key)
        loops.append({"loop": label.removesuffix(": Grashof class"), "grashof": str(value)})
    return loops


def _ranges_of(book: Book, prefix: str) -> list[dict]:
    """The summary's smallest and largest values of the output or each transmission angle."""
    found = []
    for key in _numbered(book, prefix, "_min"):
        label, low, unit = _summary_row(book, key)
        _, high, _ = _summary_row(book, key[:-4] + "_max")
        found.append({"what": label.removeprefix("smallest "), "unit": unit,
                      "min": number(low), "max": number(high)})
    return found


def _header(book: Book, sheet: str, header_row: int, letter: str) -> str:
    return _text(book, sheet, f"{letter}{header_row}")


def split_header(text: str) -> tuple[str, str]:
    """'θ14 [deg]' → ('θ14', 'deg')."""
    if text.endswith("]") and " [" in text:
        symbol, unit = text[:-1].rsplit(" [", 1)
        return symbol, unit
    return text, ""


def _angle_ranges(book: Book) -> list[dict]:
    """The smallest and largest value of every angle the Sweep sheet shows in degrees (the
    input's own column left out), read from the book's degree views."""
    sweep = book.record.sweep
    columns, rows = sweep.columns, sweep.rows
    found = []
    for key, letter in sorted(columns.items(), key=lambda kv: coordinate_to_tuple(kv[1] + "1")):
        if not key.endswith("_deg") or key == f"{book.record.input}_deg":
            continue
        numbers = [x for x in map(number, column_values(book, layout.SWEEP, letter, rows))
                   if x is not None]
        symbol, unit = split_header(_header(book, layout.SWEEP, rows[0] - 1, letter))
        found.append({"what": symbol, "unit": unit, "min": min(numbers, default=None),
                      "max": max(numbers, default=None)})
    return found


def _gaps(book: Book) -> list[dict]:
    """Every stretch of the sweep where the loop cannot close: its first and last input value
    (the sweep's gap columns, so no gap is left out)."""
    sweep = book.record.sweep
    columns, rows = sweep.columns, sweep.rows
    if "gap_from" not in columns:
        return []
    starts = [number(v) for v in column_values(book, layout.SWEEP, columns["gap_from"], rows)]
    ends = [number(v) for v in column_values(book, layout.SWEEP, columns["gap_to"], rows)]
    starts, ends = sorted(x for x in starts if x is not None), sorted(
        x for x in ends if x is not None)
    return [{"from": a, "to": b} for a, b in zip(starts, ends)]


def _peaks(book: Book, table=None, wanted=lambda key, unit: key.startswith(PEAK_PREFIXES)
           ) -> list[dict]:
    """The largest |value| down each column of a row table (the Motion sheet: each angular or
    linear velocity or acceleration) that `wanted` picks, and the input value where it
    occurs."""
    table = table or book.record.motion
    if not table:
        return []
    sheet, rows, header_row = table.sheet, table.rows, table.current_row - 1
    inputs = column_values(book, sheet, "A", rows)
    peaks = []
    for key, letter in sorted(table.columns.items(),
                              key=lambda kv: coordinate_to_tuple(kv[1] + "1")):
        symbol, unit = split_header(_header(book, sheet, header_row, letter))
        if not wanted(key, unit):
            continue
        pairs = [(abs(x), number(at)) for x, at in
                 zip(map(number, column_values(book, sheet, letter, rows)), inputs)
                 if x is not None]
        peak, at = max(pairs, default=(None, None), key=lambda p: p[0])
        peaks.append({"what": symbol, "unit": unit, "peak": peak, "at": at})
    return peaks


def _force_peaks(book: Book) -> list[dict]:
    """The Forces sheet's efforts, pin loads (their sizes) and shaking: largest |value|."""
    def wanted(key: str, unit: str) -> bool:
        return unit in ("N", "N·m") and not key.endswith(("x", "y")) and key[0] != "N"
    return _peaks(book, book.record.forces, wanted) if book.record.forces else []


def _force_summary(book: Book) -> list[dict]:
    """The Forces sheet's summary of the sweep in the book's order (the driving effort's mean,
    RMS, extremes and where, each pin's peak, for a crank the energy fluctuation, Cs and the
    flywheel inertia): each value with the label left of it (the row's nearest text: a long
    label reads on over empty cells to its value) and the unit right of it."""
    forces = book.record.forces
    if not forces:
        return []
    found = []
    for key, info in sorted(forces.summary.items(), key=lambda kv: _row_of(kv[1].cell)):
        if key.startswith(CHART_POINTS):
            continue
        row, col = coordinate_to_tuple(info.cell)
        label = next((text for c in range(col - 1, 0, -1)
                      if (text := _text(book, forces.sheet, f"{column_letter(c)}{row}"))), "")
        unit = _text(book, forces.sheet, f"{column_letter(col + 1)}{row}")
        found.append({"key": key, "what": label, "unit": unit,
                      "value": _plain(book.values.get((forces.sheet, info.cell)))})
    return found


def summary(book: Book) -> dict:
    """Everything `linkbook info` prints, as data."""
    transmissions, output = _ranges_of(book, "mu"), _ranges_of(book, "output")
    # the degree view of a transmission angle or of an angle output repeats those numbers
    # ("transmission angle μ", "θ14 (rocker, angle of B0→B)")
    shown_there = {r["what"].split()[-1] for r in transmissions} | {
        r["what"].split(" (")[0] for r in output}
    angles = [r for r in _angle_ranges(book) if r["what"] not in shown_there]
    input_head = _header(book, layout.SWEEP, book.record.sweep.rows[0] - 1, "A")
    not_closing = _summary_row(book, "not_closing")
    return {
        "book": book.name, "mechanism": book.record.mechanism,
        "title": book.record.title,
        "input": dict(zip(("symbol", "unit"), split_header(input_head))),
        "inputs": _inputs(book), "fourbar_loops": _loops(book),
        "output": output, "angles": angles,
        "transmission_angles": transmissions,
        "not_closing": number(not_closing[1]) if not_closing else 0,
        "gaps": _gaps(book), "peaks": _peaks(book), "force_peaks": _force_peaks(book),
        "force_summary": _force_summary(book), "synthesis": _synthesis(book)}


def _g(x) -> str:
    """A number as a reader wants it: 6 significant digits; '—' for none."""
    return layout.DASH if x is None else f"{x:.6g}"


def _fit(line: str, indent: int = 4) -> list[str]:
    """A line of at most WIDTH characters; a longer one wrapped, its rest indented."""
    import textwrap
    return textwrap.wrap(line, WIDTH, subsequent_indent=" " * indent) or [line]


def lines(data: dict) -> list[str]:
    """The summary as text, each line under 80 characters."""
    inp = data["input"]
    out = [*_fit(f"{data['book']}: {data['mechanism']} — {data['title']}"), "", "Inputs"]
    width = max([10, *(len(r["symbol"]) for r in data["inputs"])])   # a long name, one column
    for r in data["inputs"]:
        value = _g(r["value"]) if number(r["value"]) is not None else str(r["value"])
        out += _fit(f"  {r['symbol']:{width}} {value:>12} {r['unit']:7} {r['quantity']}",
                    width + 24)
    if data.get("synthesis"):
        out += ["", *_synthesis_lines(data["synthesis"])]
    if data["fourbar_loops"]:
        out += ["", "Four-bar loops"]
        for r in data["fourbar_loops"]:
            out += _fit(f"  {r['loop']}: {r['grashof']}")
    ranges = data["output"] + data["angles"]
    if ranges:
        out += ["", f"Over the {inp['symbol']} sweep (smallest … largest)"]
        for r in ranges:
            out += _fit(f"  {r['what']:28} {_g(r['min']):>12} … {_g(r['max']):<12} {r['unit']}")
    if data["transmission_angles"]:
        out += ["", "Transmission angles (smallest … largest)"]
        for r in data["transmission_angles"]:
            out += _fit(f"  {r['what']:28} {_g(r['min']):>12} … {_g(r['max']):<12} {r['unit']}")
    out += ["", "Where the loop cannot close"]
    if data["gaps"]:
        out += [f"  from {_g(g['from'])} to {_g(g['to'])} {inp['unit']}" for g in data["gaps"]]
    else:
        out.append(f"  it closes at every {inp['symbol']} of the sweep")
    if data["peaks"]:
        out += ["", f"Motion: largest magnitude over the sweep (at {inp['symbol']})"]
        for p in data["peaks"]:
            out += _fit(f"  {'|' + p['what'] + '|':12} {_g(p['peak']):>12} {p['unit']:9} at "
                        f"{_g(p['at'])} {inp['unit']}")
    if data.get("force_peaks"):
        out += ["", f"Forces: largest magnitude over the sweep (at {inp['symbol']})"]
        for p in data["force_peaks"]:
            out += _fit(f"  {'|' + p['what'] + '|':12} {_g(p['peak']):>12} {p['unit']:9} at "
                        f"{_g(p['at'])} {inp['unit']}")
    if data.get("force_summary"):
        out += ["", f"Forces: summary over the {inp['symbol']} sweep"]
        for r in data["force_summary"]:
            value = _g(r["value"]) if number(r["value"]) is not None else str(r["value"])
            out += _fit(f"  {r['what']:44} {value:>12} {r['unit']}")
    return out


def _synthesis_lines(syn: dict) -> list[str]:
    def shown(x) -> str:
        return _g(x) if number(x) is not None else str(x)
    kind = syn.get("kind", "function")
    out = _fit(f"Synthesis: y = {syn['f']}, {syn['points']} {syn['spacing']} precision points"
               if kind == "function" else f"Synthesis: {kind} generation, three "
               f"{'poses' if kind == 'motion' else 'points with timing'}")
    out += _fit("  designed: " + ", ".join(f"{k} = {shown(v)}"
                                           for k, v in syn["designed"].items()))
    for key in ("system", "lengths", "branch", "grashof"):
        out += _fit(f"  {key}: {syn[key]}")
    if kind != "function":
        out += _fit(f"  largest miss of the poses by the position steps: "
                    f"{shown(syn['largest_miss'])} {syn['unit']}, "
                    f"{shown(syn['largest_angle_miss'])} deg")
        return out
    out += _fit(f"  largest structural error: {shown(syn['largest_error'])} deg at x = "
                f"{shown(syn['largest_error_x'])}")
    return out
