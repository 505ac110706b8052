"""`linkbook verify`: each book's report printed (the verdict line, the checks that failed,
the other input sets) or given as JSON."""
from __future__ import annotations

from .lines import error, notes

def verify(args) -> int:
    import json
    from ..check.verifier import report_of
    reports = []
    for book in args.books:
        report = report_of(book, args.engine, args.seed)
        reports.append(report)
        notes(report.path, report.notes)
        if report.error is not None:
            error(report.error)
        elif not args.json and not (args.quiet and report.ok):
            _print_report(report, args.verbose)
            if len(args.books) > 1:
                print()
    statuses = [r.status for r in reports]
    if args.json:
        print(json.dumps([_as_data(r) for r in reports], indent=2))
    elif len(args.books) > 1 and not (args.quiet and max(statuses) == 0):
        counts = [statuses.count(k) for k in (0, 1, 2)]
        print(f"{len(args.books)} books: {counts[0]} agree, {counts[1]} disagree, "
              f"{counts[2]} cannot be verified")
    return max(statuses)


def _as_data(report) -> dict:
    """One book's report as data: the same keys whether or not it could be verified."""
    from ..base import __version__
    from ..check.verifier import TOLERANCE_RULE
    usable = report.error is None
    return {
        "book": report.path, "mechanism": report.mechanism, "engine": report.engine,
        "linkbook": __version__, "status": report.status, "ok": report.ok,
        "error": report.error, "notes": report.notes,
        "cells": report.cells, "formula_cells": report.formula_cells,
        "mismatches": report.differing,
        "likely_causes": _ranges(report, report.causes),
        "unjudged": _ranges(report, report.unjudged),
        "not_judged": _ranges(report, report.not_judged),
        "other_assembly": report.other_assembly,
        "replaced_by_constants": [f"{s}!{c}" for s, c in report.replaced],
        "stored_values_differ": report.stored_differ,
        "max_abs_diff": report.max_abs if usable else None, "inputs": report.inputs,
        "tolerance": {**TOLERANCE_RULE, "S": report.size} if usable else None,
        "checks": [c.as_dict() for c in report.checks],
        "seed": report.seed, "input_sets": _input_sets_data(report) if usable else []}


def _input_sets_data(report) -> list[dict]:
    """Each input set the formulas were judged at, the book's own first, each with the same
    keys."""
    def entry(number, inputs, changed, skipped, cells, checks, not_judged) -> dict:
        differ = differing(checks)
        return {"set": number, "inputs": inputs, "changed": changed,
                "judged": skipped is None, "not_judged_because": skipped, "cells": cells,
                "mismatches": len(differ), "differing": _ranges(report, differ),
                "not_judged": _ranges(report, not_judged),
                "max_abs_diff": max((c.max_abs for c in checks), default=0.0),
                "checks": [c.as_dict() for c in checks]}
    from ..check.checks import differing
    return [entry(1, report.inputs, [], None, report.cells, report.checks, report.not_judged),
            *(entry(s.number, s.inputs, s.changed, s.skipped, s.cells, s.checks,
                    s.not_judged()) for s in report.input_sets)]


def _in_book_order(report, cells) -> list[tuple[str, str]]:
    """(sheet, cell) pairs by the sheet's place among the book's tabs, then column, then row,
    numerically (E9 before E10)."""
    from ..base.xlsx import coordinate_to_tuple
    place = {name: i for i, name in enumerate(report.sheets)}

    def order(key):
        row, col = coordinate_to_tuple(key[1])
        return place.get(key[0], len(place)), key[0], col, row
    return sorted(cells, key=order)


def _ranges(report, cells) -> list[str]:
    """Cells as ranges in book order, a run of rows down one column as one: Sweep!E5:E77."""
    from ..check.verifier import cell_runs
    return cell_runs(_in_book_order(report, cells))


def _print_report(report, verbose: bool = False) -> None:
    """A header line, the checks (every one with `verbose`, else those that failed) with a few
    of their differing cells, and the verdict line."""
    from ..check.verifier import cell_ranges
    print(f"{report.path}: {report.mechanism}, engine {report.engine}")
    _print_checks([c for c in report.checks if verbose or not c.ok], report.causes)
    _print_input_sets(report, verbose)
    compared = f"{report.cells} of {report.formula_cells} formula cells compared"
    if report.disagrees:
        causes = cell_ranges(_in_book_order(report, report.causes))
        kinds = [f"{n} {what}" for n, what in (
            (len(report.replaced), "hold a constant where the build wrote a formula"),
            (report.stored_differ, "store a value their formula does not give")) if n]
        kinds = f" ({'; '.join(kinds)})" if kinds else ""
        unsure = "".join(f"; not judged: {what}" for what in _cannot_judge(report))
        print(f"DISAGREES: {report.differing} cells differ{kinds}, likely cause {causes}; "
              f"{compared}, max |Δ| {report.max_abs:.2e}{unsure}")
    elif report.unjudged or report.not_judged or report.other_assembly:
        print(f"CANNOT JUDGE {'; '.join(_cannot_judge(report))}; {compared}")
    else:
        skipped = [f"input set {s.number}" for s in report.input_sets if s.skipped is not None]
        scope = (f" (at the book's own inputs; {', '.join(skipped)} not judged)" if skipped
                 else "")
        print(f"all agree{scope}: {compared}, max |Δ| {report.max_abs:.2e}")


def _cannot_judge(report) -> list[str]:
    """What cannot be judged and why, each kind with its cells named."""
    from ..check.checks import DETERMINED
    from ..check.verifier import cell_ranges
    kinds = ((report.unjudged, "(the build record does not say what they hold)"),
             (report.not_judged, "too near a singular position (their rounding bound reaches "
                                 f"{DETERMINED:.0%} of their value)"))
    return [f"{_cells(len(cells))} {why}: "
            f"{cell_ranges(_in_book_order(report, cells))}" for cells, why in kinds if cells] \
        + report.other_assembly


def _print_checks(shown: list, causes) -> None:
    """The table of the checks `shown`, then a few differing cells of each: the likely causes
    first (`causes`), then cells downstream of them."""
    if shown:
        print(f"{'block':12} {'column':20} {'cells':>6} {'max |Δ|':>10} {'#N/A agree':>11}  "
              "verdict")
    for c in shown:
        verdict = "ok" if c.ok else f"{len(c.mismatches)} DIFFER"
        print(f"{c.block:12} {c.name:20} {c.cells:6d} {c.max_abs:10.2e} "
              f"{f'{c.na_agree}/{c.na_expected}':>11}  {verdict}")
    for c in shown:
        ordered = sorted(c.mismatches, key=lambda m: (m.sheet, m.cell) not in causes)
        for m in ordered[:5]:
            cause = (m.sheet, m.cell) in causes
            print(f"  {m.sheet}!{m.cell}: expected {m.expected}, got {m.got}"
                  + ("   <- likely cause (reads no differing cell)" if cause else ""))


def _print_input_sets(report, verbose: bool) -> None:
    """One line per other input set: its verdict, its inputs (those made from a zero first;
    a few where it agrees) and the cells that differ there but not at the book's own; with
    `verbose`, or where it differs, its checks."""
    from dataclasses import replace
    from ..check.verifier import cell_ranges
    own = report.differing_cells()
    for s in report.input_sets:
        if s.skipped is not None:
            print(f"input set {s.number} (seed {report.seed}) not judged: {s.skipped}")
            continue
        # where it differs, every input that shows it (to type in and see): else a few
        moved = sorted(s.changed, key=lambda k: (report.inputs.get(k) != 0, k))
        most = INPUTS_SHOWN if s.ok else len(moved)
        shown = ", ".join(f"{k}={s.inputs[k]:g}" for k in moved[:most])
        name = (f"input set {s.number} (seed {report.seed}; {shown}"
                f"{', …' if len(moved) > most else ''})")
        if s.ok:
            unsure = _in_book_order(report, s.not_judged())
            print(f"also judged at {name}: agree, {s.cells} cells compared"
                  + (f"; {_cells(len(unsure))} not judged there, too near a singular position: "
                     f"{cell_ranges(unsure)}" if unsure else ""))
        else:
            only = _in_book_order(report, s.differing() - own)
            print(f"differs at {name}: "
                  + (cell_ranges(only) if only else "the cells that differ at the book's own"))
        # the checks with cells that differ there only, as the book's own are shown
        shown = [c if verbose else replace(c, mismatches=[
            m for m in c.mismatches if (m.sheet, m.cell) not in own]) for c in s.checks]
        _print_checks([c for c in shown if verbose or not c.ok], report.causes)


INPUTS_SHOWN = 4        # of an input set's values, on its line


def _cells(n: int) -> str:
    return f"{n} formula cell{'' if n == 1 else 's'}"
