"""The `linkbook` command's arguments: the parser, its help texts and the checks of its
numbers. Imported by the command once it has the signals in hand (see cli.py)."""
from __future__ import annotations

import argparse
import math

from ..base import __version__

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


def parser():
    from .preview import PREVIEW_DPI     # the standard library and the engine's errors only
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


def _positive_int(lo: int, hi: int):
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
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number (got {text})")
    return value


def _positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not (value > 0 and value < float("inf")):
        raise argparse.ArgumentTypeError(f"must be a positive number (got {text})")
    return value
