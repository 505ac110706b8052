"""The `linkbook` command."""
from __future__ import annotations

import math
import os
import sys
from pathlib import Path

# One BLAS thread for the command. OpenBLAS starts a thread per core when numpy is first imported,
# which cost 0.07-0.12 s of CPU on every command here (2 cores), and nothing linkbook computes
# is a matrix product big enough to share out. Set before anything imports numpy; a user's own
# setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# Nothing heavy at the top: what the module imports runs before main() has the signals in hand
# (a Ctrl-C there ends in Python's traceback); each function imports what it needs.
from ..base import __version__  # noqa: E402 (after the setting above)
from ..base import stopping  # noqa: E402
from ..base.errors import InputError  # noqa: E402

EPILOG = """examples:
  linkbook list
  linkbook build fourbar                        # writes fourbar.xlsx here
  linkbook build fourbar --set a2=40 --branch crossed -o crossed.xlsx
  linkbook build slider-crank --step 1          # one row per degree
  linkbook build pump --set s1=20,50,100        # the grid's adjustments s1
  linkbook new fourbar mine.toml                # a bundled template to start from
  linkbook check mine.toml                      # check it, write nothing
  linkbook build my-linkage.toml                # your own mechanism (docs/language.md)
  linkbook build --all --outdir output          # every bundled template
  linkbook verify fourbar.xlsx                  # every formula against the reference
  linkbook animate fourbar.xlsx                 # fourbar.gif: the mechanism moving
  linkbook info fourbar.xlsx                    # its numbers: ranges, peaks, forces
  linkbook export fourbar.xlsx -o tables/       # its tables as CSV files

KEY in --set is the parameter's symbol as `linkbook list -v` shows it (a2, gamma3, ...).
Lengths are in the template's unit, angles in degrees. Exit status: 0 done, 2 bad input or a
file system that refuses the write, 130 and 143 stopped by Ctrl-C and SIGTERM."""


VERIFY_OUTPUT = """output:
  For each book, a line naming it, its mechanism and the engine, and its verdict line:
    all agree: N of N formula cells compared, max |Δ| ...
    DISAGREES: K cells differ, likely cause Sweep!E5:E77; ...     (exit 1)
    CANNOT JUDGE K formula cells ...: Mechanism!Z3; ...            (exit 2)
  (cells the build record does not describe, or too near a singular position: their
  rounding bound there reaches 1% of their value, too wide to tell a wrong formula)
  Where cells differ, the checks that failed and up to 5 of each one's cells come between
  (the likely causes first: differing cells that read no other differing cell). A book that
  cannot be verified at all ends in one line on stderr, `linkbook: error: ...` (exit 2).
  Several books end with a count of each verdict.
  -v adds the table of every check; -q leaves out the books that agree (and the count, when
  every book agrees: then nothing is printed).

  Before the verdict, one line per other input set the formulas were judged at (the vector
  engine: the book's inputs moved a little, its zeros made non-zero, drawn from --seed):
    also judged at input set 2 (seed 1; alpha_in=105.9, a1=71.63, ...): agree, N cells
    differs at input set 2 (seed 1; alpha_in=105.9, ...): Forces!D7:D79, ...     (exit 1)

  --json prints a list with one object per book, always with the same keys: book, mechanism,
  engine, linkbook (the version), status (0, 1 or 2), ok, error (null, or why the book cannot
  be verified), cells, formula_cells, mismatches (how many cells differ, at any input set),
  likely_causes, unjudged and not_judged (too near a singular position) (cell ranges in the
  book's sheet order, a run down a column as one range: "Sweep!E5:E77"), max_abs_diff, inputs,
  tolerance, checks, seed (null where only the book's own inputs were judged) and input_sets
  (the book's own first: set, inputs, changed, judged, not_judged_because, cells, mismatches,
  differing, not_judged, max_abs_diff, checks); the max_abs_diff above is the largest of
  every set's."""


def _parser():
    import argparse
    from .preview import PREVIEW_DPI     # standard library only: cheap to import
    from ..language.domain import LENGTH_UNITS
    ap = argparse.ArgumentParser(
        prog="linkbook",
        description="Turn a planar mechanism into an Excel workbook of live formulas: named "
                    "inputs, one row of RADIANS/ATAN2/ACOS steps per crank angle (or "
                    "actuator length), the current position drawn as a chart, and #N/A "
                    "wherever the loop cannot close. A "
                    "mechanism is a TOML file of the textbook's steps (crank, dyad, slider, "
                    "slide, point, slot, ...): see docs/language.md, or copy a bundled template.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"linkbook {__version__}")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", required=True)

    ls = sub.add_parser("list", help="the bundled templates, one line each")
    ls.add_argument("-v", "--verbose", action="store_true",
                    help="also list each template's parameters and defaults")

    n = sub.add_parser("new", help="copy a bundled template to a TOML file of your own",
                       description="Copy a bundled template (see `linkbook list`) to a new TOML "
                                   "file to edit: your numbers, or a mechanism of your own "
                                   "(docs/language.md). An existing file is never overwritten.")
    n.add_argument("template", metavar="NAME", help="a bundled template name")
    n.add_argument("output", metavar="MINE.toml", help="the file to write (must not exist)")

    c = sub.add_parser("check", help="check a template without writing anything",
                       description="Check a template as build does (the schema of what a "
                                   "template may contain, then its sense: points, symbols, "
                                   "lengths, the sweep) and write nothing. Exit status: 0 it "
                                   "builds, 2 it does not (one line says why and where).")
    c.add_argument("template", metavar="NAME_OR_TOML",
                   help="a bundled template name or a .toml file")

    b = sub.add_parser("build", help="write a workbook from a template",
                       description="Write a workbook from a bundled template (by name) or a "
                                   "TOML file of your own: a copy of a template with your numbers, "
                                   "or a mechanism of your own in the mechanism language "
                                   "(docs/language.md).",
                       epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    b.add_argument("template", nargs="?", metavar="NAME_OR_TOML",
                   help="a bundled template name (see `linkbook list`) or a .toml file")
    b.add_argument("-o", "--output", metavar="OUT.xlsx",
                   help="where to write (default: NAME.xlsx in the current folder)")
    b.add_argument("--set", dest="assignments", action="append", default=[],
                   metavar="KEY=VALUE", help="change a parameter, e.g. --set a2=40 (repeatable); "
                                             "a grid parameter takes a list: --set s1=20,50,100")
    b.add_argument("--step", type=str, metavar="STEP",
                   help="sweep step: degrees for a crank, the length unit for a linear actuator; a "
                        "step that does not divide the range ends with one shorter step "
                        "on the range's end, so a full turn always closes")
    b.add_argument("--branch", choices=("open", "crossed"),
                   help="assembly branch of the main loop")
    b.add_argument("--unit", choices=tuple(LENGTH_UNITS),
                   help="the book's length unit: the template's lengths are converted to it "
                        "(--set and --step values are then in this unit); every header, label, "
                        "axis title and validation message follows it")
    b.add_argument("--all", action="store_true", help="build every bundled template")
    b.add_argument("--outdir", metavar="DIR", default=None,
                   help="folder for --all (default: output)")
    b.add_argument("--values", action="store_true",
                   help="also store each formula's computed value in the file, so viewers that "
                        "do not calculate (previews, pandas, openpyxl data_only) show numbers")

    v = sub.add_parser("verify", help="re-check a workbook against the independent reference",
                       description="Evaluate every formula cell of a linkbook workbook (with the "
                                   "inputs it holds now, even after editing in Excel) and compare "
                                   "it with the independent Newton-Raphson reference: |Δ| ≤ 1e-12 "
                                   "times the mechanism's size for a length, 1e-9 for an angle; "
                                   "#N/A exactly where the loop cannot close. A formula cell the "
                                   "book's build record does not describe is named, not passed. "
                                   "Exit status: 0 every formula cell agrees, 1 a cell disagrees, "
                                   "2 the file cannot be verified (one line says why and where).",
                       epilog=VERIFY_OUTPUT, formatter_class=argparse.RawDescriptionHelpFormatter)
    v.add_argument("books", nargs="+", metavar="BOOK.xlsx",
                   help="one or more workbooks; the exit status is the worst of theirs")
    v.add_argument("--engine", choices=("vector", "formulas", "libreoffice", "gnumeric"),
                   default="vector",
                   help="vector (default, fast: one compiled formula per column shape), formulas "
                        "(the full ExcelModel, slow), libreoffice (recalculate in soffice), "
                        "gnumeric (recalculate in Gnumeric's ssconvert)")
    v.add_argument("--json", action="store_true",
                   help="print the reports as JSON: a list, one object per book (see below)")
    v.add_argument("--seed", type=_positive_int(0, 2 ** 31 - 1), default=None, metavar="N",
                   help="the seed of the other input set the formulas are judged at (default "
                        "1); the same seed draws the same set")
    amount = v.add_mutually_exclusive_group()
    amount.add_argument("-q", "--quiet", action="store_true",
                        help="print only the books that do not agree (the exit status says the "
                             "rest)")
    amount.add_argument("-v", "--verbose", action="store_true",
                        help="also print every check: each column or block compared, its cells, "
                             "max |Δ| and #N/A agreement")

    a = sub.add_parser("animate", help="write a GIF (or MP4) of the mechanism moving through its "
                                       "sweep",
                       description="Draw the mechanism at every input value of the book's sweep "
                                   "(or by --step) and write the frames as a looping GIF: links "
                                   "coloured as in the workbook's drawing, fixed pivots marked, "
                                   "the traced point's path as it forms, equal scales on x and "
                                   "y, the input value on each frame. Each frame is the book's "
                                   "own drawing data, evaluated with the input cell set to that "
                                   "value, so a book edited in Excel animates as edited; values "
                                   "where the loop cannot close (#N/A) are left out, with a "
                                   "note on the frames. An .mp4 output (H.264) needs the "
                                   "imageio-ffmpeg package: pip install 'linkbook[video]'.",
                       epilog="examples:\n  linkbook animate fourbar.xlsx            # fourbar.gif "
                              "beside it\n  linkbook animate jansen.xlsx -o leg.gif --step 2 "
                              "--fps 30 --size 800\n  linkbook animate pump.xlsx -o pump.mp4",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("book", metavar="BOOK.xlsx")
    a.add_argument("-o", "--output", metavar="OUT.gif",
                   help="where to write, .gif or .mp4; with --at a .png or .svg (default: "
                        "BOOK.gif, or BOOK-at-VALUE.png, next to the book)")
    a.add_argument("--at", type=_finite_float, default=None, metavar="VALUE",
                   help="one picture of the mechanism at this input value (degrees, or the "
                        "length unit for a linear actuator) instead of a moving one")
    a.add_argument("--fps", type=_positive_int(1, 100), default=20,
                   help="frames per second (1-100, default 20)")
    a.add_argument("--size", type=_positive_int(100, 4000), default=600,
                   help="width and height in pixels (100-4000, default 600; even for an .mp4)")
    a.add_argument("--step", type=_positive_float, default=None,
                   help="input step between frames (degrees, or the length unit for a linear "
                        "actuator; default: the book's sweep step)")

    p = sub.add_parser("preview", help="print a workbook's sheets to PDF and PNG",
                       description="Print the workbook with LibreOffice to BOOK.pdf, and each "
                                   "printed page to BOOK-SHEET-N.png with pdftoppm (needs "
                                   "soffice and poppler-utils).",
                       epilog="examples:\n  linkbook preview fourbar.xlsx --sheet Mechanism "
                              "--dpi 150\n  linkbook preview pump.xlsx --sheet Grid --sheet "
                              "Charts -o pictures/",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("book", metavar="BOOK.xlsx")
    p.add_argument("-o", "--outdir", metavar="DIR", default=None,
                   help="folder for the PDF and PNGs (default: BOOK_preview next to the book)")
    p.add_argument("--sheet", action="append", metavar="NAME", default=None,
                   help="a sheet to print (repeat for more; default: every visible sheet)")
    p.add_argument("--dpi", type=_positive_int(30, 600), default=PREVIEW_DPI,
                   help=f"resolution of the PNGs (30-600, default {PREVIEW_DPI})")
    _info_parsers(sub)
    return ap


def _info_parsers(sub) -> None:
    """`info` and `export`: a book's numbers, as its own formulas compute them."""
    import argparse
    from textwrap import fill
    i = sub.add_parser("info", help="a summary of a book's (or a template's) numbers",
                       description=fill("Summarise a workbook, or a template built in memory (nothing "
                                   "is written): its inputs with units, the Grashof class of "
                                   "each four-bar loop, the range of the output and of each "
                                   "angle over the sweep, each transmission angle's range, the "
                                   "gaps where the loop cannot close, the largest |ω|, |α|, "
                                   "speed and acceleration of the Motion sheet and, with forces, "
                                   "the largest efforts and pin loads and the Forces sheet's "
                                   "summary (mean effort, RMS, extremes and where, each pin's "
                                   "peak, energy fluctuation, flywheel inertia). Every number is "
                                   "computed by linkbook's engine from the book's own formulas, "
                                   "so a book edited in Excel reports its edited values.", 79),
                       epilog="examples:\n  linkbook info fourbar.xlsx\n  linkbook info "
                              "fourbar\n  linkbook info mine.toml --json\n\n"
                              + fill("--json prints one object: book, mechanism, title, input "
                                     "(symbol, unit), inputs, fourbar_loops, output, angles, "
                                     "transmission_angles (each: what, unit, min, max), "
                                     "not_closing, gaps (from, to), peaks and force_peaks "
                                     "(what, unit, peak, at), force_summary (key, what, unit, "
                                     "value).", 79),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    i.add_argument("book", metavar="BOOK.xlsx|NAME_OR_TOML",
                   help="a workbook, a bundled template name or a .toml file")
    i.add_argument("--json", action="store_true", help="print the summary as a JSON object")
    e = sub.add_parser("export", help="write a book's tables as CSV files",
                       description=fill("Write each table sheet of a workbook (Sweep, Motion, Grid, "
                                   "Stroke sweep: those it has) to DIR/BOOK-SHEET.csv (a "
                                   "space in a sheet's name written as -): the "
                                   "header rows as in the book, then one line per row, with "
                                   "the values linkbook's engine computes from the book's "
                                   "formulas (a book saved without values exports numbers "
                                   "too). Numbers in full precision (Python's repr); an error "
                                   "value as its code, #N/A where the loop cannot close; a "
                                   "text that starts with =, +, -, @, a tab or a carriage "
                                   "return prefixed with ' (so that no spreadsheet opening the "
                                   "CSV runs it as a formula); UTF-8 with a byte-order mark, "
                                   "comma-separated.", 79),
                       epilog="examples:\n  linkbook export fourbar.xlsx -o tables/",
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    e.add_argument("book", metavar="BOOK.xlsx")
    e.add_argument("-o", "--outdir", metavar="DIR", default=None,
                   help="folder for the CSV files (default: BOOK_csv next to the book)")


def run() -> None:
    """The `linkbook` command and `python -m linkbook`: main(), then the process ends at once.
    By then everything a command makes is closed (files written and renamed into place,
    LibreOffice waited for); what Python's own exit would add is freeing the book's hundreds of
    thousands of objects one by one and tearing down every module: 30-60 ms of a 0.3-0.5 s build
    or verify, measured here. The exit handlers still run (openpyxl removes its temporary files
    after a failed save, coverage saves its data), and under a profiler or tracer, which reports
    after we return, the exit is Python's own. Callers of main() (the tests, the API) keep a
    normal return."""
    with stopping.handled():      # first: from here to the exit a signal ends in one line
        status = main()
        if sys.getprofile() is not None or sys.gettrace() is not None:
            raise SystemExit(status)
        with stopping.held():     # one that comes now is looked at once, just before the exit
            _finish()
            stop = stopping.arrived()
            if stop is not None and status not in STOPPED_STATUSES:
                _say_stopped(stop[0])
                status = stop[1]
            os._exit(status)


def _finish() -> None:
    """What Python's own exit would do that matters: the exit handlers, the streams flushed."""
    import atexit
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        if stream is None:          # started with the stream closed
            continue
        try:
            stream.flush()
        except BrokenPipeError:     # the reader stopped early, as in main()
            _to_devnull(stream)
        except (OSError, ValueError):
            pass


def _say_stopped(what: str) -> None:
    print(f"linkbook: stopped by {what}; no file is left half-written", file=sys.stderr,
          flush=True)


STOPPED_STATUSES = {status for _, _, status in stopping.STOPS.values()}


def _to_devnull(stream) -> None:
    os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())


def main(argv: list[str] | None = None) -> int:
    # Everything inside the try, from the first line on: a Ctrl-C that lands while the command
    # is still being imported ends in the same one line as one that lands mid-work.
    try:
        import warnings
        with stopping.handled(), warnings.catch_warnings():
            # numpy's overflow warnings on extreme inputs would only repeat what the answer
            # says, and no user should see a line of our source code
            warnings.simplefilter("ignore")
            status = _main(argv)
            stopping.stop_if_signalled()     # one whose raise was swallowed where it landed
            return status
    except BrokenPipeError:
        # The reader stopped early (`linkbook list | head`): not an error. Point stdout at
        # /dev/null so that Python's own flush at exit does not complain either.
        _to_devnull(sys.stdout)
        return 0
    except BaseException as exc:
        # a stop, or anything a stop turned into on its way out (a library's own error)
        stop = stopping.stop_of(exc) or stopping.arrived()
        if stop is not None:
            what, status = stop      # the shell's convention: 128 + the signal's number
            _say_stopped(what)
            return status
        if not isinstance(exc, Exception):      # SystemExit: argparse's own exit
            raise
        # A bug of ours, not the user's input: still one line, never a traceback.
        print(f"linkbook: internal error: {type(exc).__name__}: {_one_line(exc)} (please "
              "report it with the file that caused it)", file=sys.stderr)
        return 2


def _main(argv: list[str] | None) -> int:
    from ..base.files import CannotWrite
    args = _parser().parse_args(argv)
    try:
        if args.command == "list":
            return _list(args.verbose)
        if args.command == "build":
            return _build(args)
        if args.command == "new":
            return _new(args)
        if args.command == "check":
            return _check(args)
        if args.command == "verify":
            return _verify(args)
        if args.command == "preview":
            return _preview(args)
        if args.command == "animate":
            return _animate(args)
        if args.command == "info":
            return _info(args)
        if args.command == "export":
            return _export(args)
    except (InputError, CannotWrite) as exc:
        _error(exc)
        return 2
    return 0


def _error(exc: Exception) -> None:
    """The one line a failure ends with, on stderr: whole (it names the field and the value),
    its line breaks, if any, joined."""
    print(f"linkbook: error: {' '.join(str(exc).split())}", file=sys.stderr)


def _notes(path, notes) -> None:
    """What a book holds that leaves its numbers alone, one warning line each on stderr."""
    for note in notes:
        print(f"linkbook: warning: {path}: {note}", file=sys.stderr)


def _verify(args) -> int:
    import json
    from ..check.verifier import report_of
    reports = []
    for book in args.books:
        report = report_of(book, args.engine, args.seed)
        reports.append(report)
        _notes(report.path, report.notes)
        if report.error is not None:
            _error(report.error)
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


def _one_line(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 300 else text[:297] + "..."


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
    elif report.unjudged or report.not_judged:
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
            f"{cell_ranges(_in_book_order(report, cells))}" for cells, why in kinds if cells]


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


def _positive_int(lo: int, hi: int):
    import argparse
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be from {lo} to {hi} (got {value})")
        return value
    return parse


def _finite_float(text: str) -> float:
    import argparse
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number (got {text})")
    return value


def _positive_float(text: str) -> float:
    import argparse
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number (got {text})")
    return value


def _info(args) -> int:
    import json
    from . import info
    from ..check.verifier import UnusableFile
    try:
        book = (info.open_book(Path(args.book)) if args.book.lower().endswith(".xlsx")
                else info.built_book(args.book))
        data = info.read_record(book, info.summary)
    except UnusableFile as exc:
        _error(exc)
        return 2
    _notes(book.name, getattr(book.wb, "notes", ()))
    print(json.dumps(data, indent=2, ensure_ascii=False) if args.json
          else "\n".join(info.lines(data)))
    return 0


def _export(args) -> int:
    from .export import export, table_texts
    from ..base.files import ensure_folder
    from .info import open_book, read_record
    from ..check.verifier import UnusableFile
    book = Path(args.book)
    try:
        opened = open_book(book)
        texts = read_record(opened, table_texts)
    except UnusableFile as exc:
        _error(exc)
        return 2
    _notes(book, getattr(opened.wb, "notes", ()))
    outdir = ensure_folder(Path(args.outdir) if args.outdir
                           else book.with_name(book.stem + "_csv"), "--outdir")
    for path in export(texts, book.stem, outdir):
        print(f"wrote {path}")
    return 0


def _animate(args) -> int:
    from .animate import frames_of, render, terminal_progress, write_video
    from ..base.files import write_atomic
    book = Path(args.book)
    if args.at is not None:
        return _picture(args, book)
    out = Path(args.output) if args.output else book.with_suffix(".gif")
    kind = out.suffix.lower().lstrip(".")
    if kind not in ("gif", "mp4"):
        raise InputError("--output", f"a .gif or .mp4 file (got {out.name}; a .png or .svg "
                                     "is one picture: give --at VALUE)")
    if kind == "mp4" and args.size % 2:
        raise InputError("--size", f"must be even for an .mp4 (got {args.size}): its frames "
                                   "are made of 2 × 2 blocks")

    def work():
        anim = frames_of(book, args.step)
        images = render(anim, args.size, terminal_progress())
        write_atomic(out, lambda tmp: write_video(images, tmp, args.fps, kind))
        return anim, images
    done = _drawing(book, out, work)
    if done is None:
        return 2
    anim, images = done
    skipped = len(anim.frames) - len(anim.drawn)
    note = f" ({skipped} left out: the loop cannot close there)" if skipped else ""
    print(f"wrote {out}: {len(images)} frames{note}")
    return 0


def _drawing(book: Path, out: Path, work):
    """What work() returns, or None after one error line: the book missing or unusable, or
    `out` not written. Shared by the animation and the single picture."""
    from .animate import AnimationError
    from ..base.safety import UnsafeFile
    try:
        if not book.is_file():
            raise AnimationError(f"{book}: no such file")
        return work()
    except OSError as exc:
        # the output's own refusal names it; any other (reading the book, a font) its file
        what = f"cannot write {out}" if exc.filename in (None, str(out)) else exc.filename
        print(f"linkbook: error: {what}: {exc.strerror or exc}", file=sys.stderr)
    except (AnimationError, UnsafeFile) as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
    return None


def _picture(args, book: Path) -> int:
    """`animate --at VALUE`: the mechanism at one input value, as PNG or SVG."""
    from .animate import AnimationError, frame_at, render, write_svg
    from ..base.files import write_atomic
    out = Path(args.output) if args.output else book.with_name(f"{book.stem}-at-{args.at:g}.png")
    kind = out.suffix.lower().lstrip(".")
    if kind not in ("png", "svg"):
        raise InputError("--output", f"with --at, a .png or .svg file (got {out.name})")
    def work():
        anim = frame_at(book, args.at)
        if not anim.drawn:
            raise AnimationError(f"{book}: the loop cannot close at {anim.symbol} = {args.at:g}")
        if kind == "svg":
            write_atomic(out, lambda tmp: write_svg(anim, tmp, args.size))
        else:
            image = render(anim, args.size)[0]
            write_atomic(out, lambda tmp: image.save(tmp, format="PNG"))
        return anim
    anim = _drawing(book, out, work)
    if anim is None:
        return 2
    print(f"wrote {out}: the mechanism at {anim.symbol} = {args.at:g} {anim.unit}".rstrip())
    return 0


def _preview(args) -> int:
    from ..base.files import ensure_folder
    from ..engine.office import OfficeUnavailable
    from .preview import preview, visible_sheets
    from ..base.safety import UnsafeFile, check_zip
    book = Path(args.book)
    try:
        check_zip(book)
        sheets = _chosen_sheets(book, args.sheet, visible_sheets(book))
        outdir = ensure_folder(Path(args.outdir) if args.outdir
                               else book.with_name(book.stem + "_preview"), "--outdir")
        pictures = preview(book, outdir, dpi=args.dpi, sheets=sheets)
        print(f"wrote {outdir / (book.stem + '.pdf')}")
        for png in pictures:
            print(f"wrote {png}")
    except (UnsafeFile, OfficeUnavailable) as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
        return 2
    return 0


def _chosen_sheets(book: Path, asked: list[str] | None, visible: list[str]) -> list[str]:
    """The sheets --sheet names, in the book's order, each a visible sheet of the book."""
    for name in asked or []:
        if name not in visible:
            raise InputError("--sheet", f"{book.name} has no visible sheet {name!r} (it has "
                                        f"{', '.join(visible)})")
    return [name for name in visible if name in asked] if asked else visible


def _list(verbose: bool) -> int:
    from ..language import templates
    for path in templates.bundled():
        t = templates.load(str(path))
        steps = ", ".join(dict.fromkeys(s["type"] for s in t.mechanism.description["steps"]))
        print(f"{t.name:24} {t.title}  [{steps}]")
        if verbose:
            for p in t.parameters:
                made = f" (designed by {p.designed_by})" if p.designed_by else ""
                print(f"    {p.symbol:12} = {p.value:<10g} {p.unit:4} {p.label}{made}")
    return 0


def _new(args) -> int:
    from ..language import templates
    out = templates.copy_bundled(args.template, Path(args.output))
    print(f"wrote {out}: the bundled {args.template}; edit it, then `linkbook check {out}` "
          f"and `linkbook build {out}`")
    return 0


def _check(args) -> int:
    from ..book.builder import make
    from ..language import templates
    t = templates.load(args.template)
    built, _ = make(t, values_needed=False)
    _warn(built)
    print(f"{args.template}: ok ({len(t.mechanism.description['steps'])} steps, "
          f"{len(t.parameters)} parameters)")
    return 0


def _warn(built) -> None:
    """What the user should know about a book that is not an error (a loop that cannot close
    over part of the sweep): one line each on stderr."""
    for line in built.warnings:
        print(f"linkbook: warning: {line}", file=sys.stderr)


def _build(args) -> int:
    # imported by the commands that read a template, not by the module: verify reads none
    from ..language import templates
    if args.all:
        if args.template or args.output or args.assignments or args.step or args.branch \
                or args.unit:
            raise InputError("--all", "builds the bundled templates as they are; give no "
                                      "template, -o, --set, --step, --branch or --unit with it")
        from ..base.files import ensure_folder
        outdir = ensure_folder(Path(args.outdir or "output"), "--outdir")
        from ..book.builder import build_file
        for path in templates.bundled():
            t = templates.load(str(path))
            out = outdir / f"{t.name}.xlsx"
            _warn(build_file(t, out, args.values))
            print(f"wrote {out}")
        return 0
    if not args.template:
        raise InputError("build", "give a template name or .toml file, or --all")
    if args.outdir:
        raise InputError("--outdir", "goes with --all; use -o for one workbook")
    t = templates.load(args.template)
    if args.unit:
        t = templates.with_unit(t, args.unit)
    t = templates.with_overrides(t, args.assignments, args.step, args.branch)
    from ..base.files import check_output
    out = check_output(Path(args.output or f"{t.name}.xlsx"), "-o", (".xlsx",))
    from ..book.builder import build_file
    _warn(build_file(t, out, args.values))
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    run()
