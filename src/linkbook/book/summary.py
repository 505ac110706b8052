"""The Mechanism sheet's geometry summary: live formulas that say where the mechanism assembles,
how far its output swings, the range of every transmission angle, and for each four-bar loop on
the ground its Grashof class and the input's limit angles.
"""
from __future__ import annotations

from openpyxl.styles import Alignment
from openpyxl.utils import quote_sheetname

from ..base.sheets import DASH, GAPS_SHOWN, SWEEP, summary_prefix
from ..language.excel import render
from ..language.model import DEG, LENGTH, RAD, Model
from .resolve import Resolver
from ..language.excel import outside_domain
from ..language.templates import Template
from .style import (BOLD, DERIVED_FILL, column_range, number_format, put_text, set_formula,
                    unit_text, wrap_across)
from .sweep import numbers_place


def summary_block(ws, t: Template, model: Model, names: dict, sweep: dict, row: int) -> dict:
    """Geometry honesty, as live formulas: where the mechanism assembles, its swing, the range
    of every transmission angle, and for every four-bar loop on the ground its Grashof class and
    the input's limit angles. Ranges are read from the numbers-only copies beside the sweep
    table (sweep_numbers_only)."""
    if not model.closes:
        return {}
    cols, (r0, r1) = sweep["columns"], sweep["rows"]
    src = quote_sheetname(SWEEP)

    def rng(key: str) -> str:
        return f"{src}!${cols[key]}${r0}:${cols[key]}${r1}"

    ws[f"A{row}"] = f"Geometry summary (over the {t.mechanism.input_symbol} sweep on sheet {SWEEP})"
    ws[f"A{row}"].font = BOLD
    row += 1
    cells: dict[str, dict] = {}

    def add(key: str, label: str, formula: str, unit: str = "", kind: str = "number") -> str:
        nonlocal row
        put_text(ws, f"A{row}", label)
        wrap_across(ws, row, "A", "B", label)
        c = set_formula(ws[f"C{row}"], formula)
        c.fill = DERIVED_FILL
        c.number_format = number_format(unit, t.length_unit) if unit else "General"
        # a text value (a Grashof class) reads on into the empty cells to its right
        c.alignment = Alignment(horizontal="left" if kind == "text" else "right")
        if unit:
            put_text(ws, f"D{row}", unit_text(unit, t.length_unit))
        cells[key] = {"cell": f"C{row}", "kind": kind, "unit": unit}
        row += 1
        return f"$C${row - 1}"

    w = rng("closes")
    word = t.mechanism.input_word
    add("assembles_all", f"assembles at every {word} of the sweep",
        f'=IF(SUM({w})=ROWS({w}),"yes","no")', kind="text")
    add("not_closing", f"{word}s where the loop cannot close", f"=ROWS({w})-SUM({w})")
    first_failing = f'"{DASH}"'
    for key, (_, name) in reversed(list(zip(model.closes, model.loop_steps))):
        first_failing = f'IF(COUNT({rng(key)})<ROWS({rng(key)}),"{name}",{first_failing})'
    add("failing_step", "first loop step that cannot close", "=" + first_failing, kind="text")
    for k in range(1, GAPS_SHOWN + 1):
        add(f"gap{k}_from", f"gap {k}: cannot close from",
            f'=IFERROR(SMALL({rng("gap_from")},{k}),"{DASH}")', t.mechanism.input_unit,
            "number_or_dash")
        add(f"gap{k}_to", f"gap {k}: … to", f'=IFERROR(SMALL({rng("gap_to")},{k}),"{DASH}")',
            t.mechanism.input_unit, "number_or_dash")

    copies = numbers_place(t, model)[0]

    def numbers_of(key: str) -> str:
        """The range of the numbers-only copy of sweep column `key` (sweep_numbers_only)."""
        return column_range(SWEEP, copies[key], r0, r1)

    def extremes(prefix: str, what: str, key: str, unit: str, convert: str = "") -> list[str]:
        column = numbers_of(key)
        cells = []
        for suffix, fn, word in (("min", "MIN", "smallest"), ("max", "MAX", "largest")):
            value = f"{fn}({column})"
            value = f"{convert}({value})" if convert else value
            cells.append(add(f"{prefix}_{suffix}", f"{word} {what}",
                             f'=IF(COUNT({column})=0,"{DASH}",{value})', unit, "number_or_dash"))
        return cells

    if model.output:
        q = model.get(model.output)
        if q.unit == RAD:
            # an angle (a rocker's): its degree view, whose window keeps the swing in one piece
            low, high = extremes("output", f"{q.symbol} ({q.label})", f"{q.key}_deg", DEG)
            add("output_swing", f"swing of {q.symbol} (largest − smallest)",
                f'=IF(ISNUMBER({low}),{high}-{low},"{DASH}")', DEG, "number_or_dash")
        else:
            extremes("output", f"{q.symbol} ({q.label})", model.output, q.unit)
    for i, key in enumerate(model.transmissions, start=1):
        # read in radians: a degree view's window moves with the data, μ lies in [0, π]
        extremes(summary_prefix("mu", i), f"transmission angle {model.get(key).symbol}",
                 key, DEG, convert="DEGREES")
    for i, loop in enumerate(model.fourbars, start=1):
        _fourbar_summary(add, loop, summary_prefix("", i), Resolver(model, names, {}))
    return cells


def grashof_formula(g: str, c: str, k: str, r: str) -> str:
    """Grashof's class, as Excel text, of a four-bar of ground g, crank c, coupler k and rocker
    r (cells or expressions)."""
    links = f"{g},{c},{k},{r}"
    shortest, longest = f"MIN({links})", f"MAX({links})"
    others = f"({g}+{c}+{k}+{r}-{shortest}-{longest})"
    return (f'IF({shortest}+{longest}>{others}*(1+1E-12),"non-Grashof: triple rocker",'
            f'IF({shortest}+{longest}>={others}*(1-1E-12),"change point",'
            f'IF({shortest}={g},"Grashof: double crank",IF({shortest}={c},'
            f'"Grashof: crank-rocker",IF({shortest}={k},"Grashof: double rocker",'
            f'"Grashof: rocker-crank")))))')


def _fourbar_summary(add, fb, n: str, resolve) -> None:
    what = f"four-bar loop {fb.name}"
    g = add(f"fb{n}_ground", f"{what}: ground link", "=" + render(fb.ground, resolve), LENGTH)
    c = add(f"fb{n}_crank", f"{what}: input crank", "=" + render(fb.crank, resolve), LENGTH)
    k = add(f"fb{n}_coupler", f"{what}: coupler", "=" + render(fb.coupler, resolve), LENGTH)
    r = add(f"fb{n}_rocker", f"{what}: output link", "=" + render(fb.rocker, resolve), LENGTH)
    add(f"grashof{n}", f"{what}: Grashof class", "=" + grashof_formula(g, c, k, r),
        kind="text")
    ground_angle = render(fb.ground_angle, resolve)
    for name, length in (("stretched", f"({k}+{r})"), ("folded", f"ABS({k}-{r})")):
        cosine = f"({g}^2+{c}^2-{length}^2)/(2*{g}*{c})"
        lo = f"MOD(DEGREES({ground_angle}-ACOS({cosine})),360)"
        hi = f"MOD(DEGREES({ground_angle}+ACOS({cosine})),360)"
        # the cosine's domain tested, not ACOS's error caught (IronCalc's ACOS(2) is a NaN
        # that IFERROR lets through);
        # IFERROR: a length edited to 0 divides by zero, and there is no limit angle either
        none = outside_domain("ACOS", cosine)
        add(f"limit{n}_{name}_1", f"{what}: input limit angle, coupler and output link {name}",
            f'=IFERROR(IF({none},"none",MIN({lo},{hi})),"none")', DEG, "number_or_none")
        add(f"limit{n}_{name}_2", "… and the other one",
            f'=IFERROR(IF({none},"none",MAX({lo},{hi})),"none")', DEG, "number_or_none")
