"""The `linkbook` command."""
from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

# One BLAS thread for the command. OpenBLAS starts a thread per core when numpy is first imported,
# which cost 0.07-0.12 s of CPU on every command here (2 cores), and nothing linkbook computes
# is a matrix product big enough to share out. Set before anything imports numpy; a user's own
# setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from . import __version__, templates  # noqa: E402 (after the setting above)
from .templates import InputError

EPILOG = """examples:
  linkbook list
  linkbook build fourbar                        # writes fourbar.xlsx here
  linkbook build fourbar --set a2=40 --branch crossed -o crossed.xlsx
  linkbook build slider-crank --step 1          # one row per degree
  linkbook build pump --set s1=20,50,100        # the grid's adjustments s1
  linkbook build my-linkage.toml                # your own mechanism (docs/language.md)
  linkbook build --all --outdir output          # every bundled template
  linkbook verify fourbar.xlsx                  # every formula against the reference
  linkbook animate fourbar.xlsx                 # fourbar.gif: the mechanism moving

KEY in --set is the parameter's symbol as `linkbook list -v` shows it (a2, gamma3, ...).
Lengths are in the template's unit, angles in degrees. Exit status: 0 done, 2 bad input."""


def _parser() -> argparse.ArgumentParser:
    from .office import PREVIEW_DPI     # standard library only: cheap to import
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
    b.add_argument("--unit", choices=tuple(templates.LENGTH_UNITS),
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
                                   "2 the file cannot be verified (one line says why and where).")
    v.add_argument("books", nargs="+", metavar="BOOK.xlsx",
                   help="one or more workbooks; the exit status is the worst of theirs")
    v.add_argument("--engine", choices=("vector", "formulas", "libreoffice"), default="vector",
                   help="vector (default, fast: one compiled formula per column shape), formulas "
                        "(the full ExcelModel, slow), libreoffice (recalculate in soffice)")
    v.add_argument("--json", action="store_true", help="print the report as JSON")

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
    return ap


def run() -> None:
    """The `linkbook` command and `python -m linkbook`: main(), then the process ends at once.
    By then everything a command makes is closed (files written and renamed into place,
    LibreOffice waited for); what Python's own exit would add is freeing the book's hundreds of
    thousands of objects one by one and tearing down every module: 30-60 ms of a 0.3-0.5 s build
    or verify, measured here. The exit handlers still run (openpyxl removes its temporary files
    after a failed save, coverage saves its data), and under a profiler or tracer, which reports
    after we return, the exit is Python's own. Callers of main() (the tests, the API) keep a
    normal return."""
    import atexit
    status = main()
    if sys.getprofile() is not None or sys.gettrace() is not None:
        raise SystemExit(status)
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
    os._exit(status)


def _to_devnull(stream) -> None:
    os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())


def main(argv: list[str] | None = None) -> int:
    import warnings
    try:
        with warnings.catch_warnings():
            # numpy's overflow warnings on extreme inputs would only repeat what the answer
            # says, and no user should see a line of our source code
            warnings.simplefilter("ignore")
            return _main(argv)
    except BrokenPipeError:
        # The reader stopped early (`linkbook list | head`): not an error. Point stdout at
        # /dev/null so that Python's own flush at exit does not complain either.
        _to_devnull(sys.stdout)
        return 0
    except Exception as exc:
        # A bug of ours, not the user's input: still one line, never a traceback.
        print(f"linkbook: internal error: {type(exc).__name__}: {_one_line(exc)} (please "
              "report it with the file that caused it)", file=sys.stderr)
        return 2


def _main(argv: list[str] | None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "list":
            return _list(args.verbose)
        if args.command == "build":
            return _build(args)
        if args.command == "verify":
            return _verify(args)
        if args.command == "preview":
            return _preview(args)
        if args.command == "animate":
            return _animate(args)
    except InputError as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
        return 2
    return 0


def _verify(args) -> int:
    import json
    statuses, reports = [], []
    for book in args.books:
        status, report = _verify_one(book, args.engine, quiet=args.json)
        statuses.append(status)
        reports.append(report)
        if not args.json and len(args.books) > 1:
            print()
    if args.json:
        print(json.dumps(reports[0] if len(reports) == 1 else reports, indent=2))
    elif len(args.books) > 1:
        counts = [statuses.count(k) for k in (0, 1, 2)]
        print(f"{len(args.books)} books: {counts[0]} agree, {counts[1]} disagree, "
              f"{counts[2]} cannot be verified")
    return max(statuses)


def _verify_one(book: str, engine: str, quiet: bool) -> tuple[int, dict]:
    """(exit status, the report as data) of one book; the text report is printed unless
    `quiet`, an error line always."""
    from . import __version__
    from .office import OfficeFailed, OfficeUnavailable
    from .safety import UnsafeFile
    from .verifier import TOLERANCE_RULE, UnusableFile, verify
    try:
        report = verify(Path(book), engine)
    except (UnusableFile, UnsafeFile, OfficeUnavailable, OfficeFailed) as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
        return 2, {"book": book, "status": 2, "error": str(exc), "linkbook": __version__}
    if not quiet:
        _print_report(report)
    return report.status, {
        "book": report.path, "mechanism": report.mechanism, "engine": report.engine,
        "linkbook": __version__, "ok": report.ok, "status": report.status,
        "cells": report.cells, "formula_cells": report.formula_cells,
        "mismatches": report.differing,
        "likely_causes": [f"{s}!{c}" for s, c in sorted(report.causes)],
        "unjudged": [f"{s}!{c}" for s, c in report.unjudged],
        "max_abs_diff": report.max_abs, "inputs": report.inputs,
        "tolerance": {**TOLERANCE_RULE, "S": report.size},
        "checks": [c.as_dict() for c in report.checks]}


def _one_line(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 300 else text[:297] + "..."


def _print_report(report) -> None:
    from .verifier import cell_order, cell_ranges
    print(f"{report.path}: {report.mechanism}, engine {report.engine}")
    print(f"{'block':12} {'column':20} {'cells':>6} {'max |Δ|':>10} {'#N/A agree':>11}  verdict")
    for c in report.checks:
        verdict = "ok" if c.ok else f"{len(c.mismatches)} DIFFER"
        print(f"{c.block:12} {c.name:20} {c.cells:6d} {c.max_abs:10.2e} "
              f"{f'{c.na_agree}/{c.na_expected}':>11}  {verdict}")
    for c in report.checks:
        # the likely causes first, then a few of the cells downstream of them
        ordered = sorted(c.mismatches, key=lambda m: (m.sheet, m.cell) not in report.causes)
        for m in ordered[:5]:
            cause = (m.sheet, m.cell) in report.causes
            print(f"  {m.sheet}!{m.cell}: expected {m.expected}, got {m.got}"
                  + ("   <- likely cause (reads no differing cell)" if cause else ""))
    compared = f"{report.cells} of {report.formula_cells} formula cells compared"
    if report.disagrees:
        causes = cell_ranges(sorted(report.causes, key=cell_order))
        print(f"DISAGREES: {report.differing} cells differ, likely cause {causes}; {compared}, "
              f"max |Δ| {report.max_abs:.2e}")
    elif report.unjudged:
        print(f"CANNOT JUDGE {len(report.unjudged)} formula cells (the build record does not "
              f"say what they hold): {cell_ranges(report.unjudged)}; {compared}")
    else:
        print(f"all agree: {compared}, max |Δ| {report.max_abs:.2e}")


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


def _animate(args) -> int:
    from .animate import AnimationError, frames_of, render, terminal_progress, write_video
    from .files import write_atomic
    from .safety import UnsafeFile
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
    try:
        if not book.is_file():
            raise AnimationError(f"{book}: no such file")
        anim = frames_of(book, args.step)
        images = render(anim, args.size, terminal_progress())
        write_atomic(out, lambda tmp: write_video(images, tmp, args.fps, kind))
    except OSError as exc:
        print(f"linkbook: error: cannot write {out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except (AnimationError, UnsafeFile) as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
        return 2
    skipped = len(anim.frames) - len(anim.drawn)
    note = f" ({skipped} left out: the loop cannot close there)" if skipped else ""
    print(f"wrote {out}: {len(images)} frames{note}")
    return 0


def _picture(args, book: Path) -> int:
    """`animate --at VALUE`: the mechanism at one input value, as PNG or SVG."""
    from .animate import AnimationError, frame_at, render, write_svg
    from .files import write_atomic
    from .safety import UnsafeFile
    out = Path(args.output) if args.output else book.with_name(f"{book.stem}-at-{args.at:g}.png")
    kind = out.suffix.lower().lstrip(".")
    if kind not in ("png", "svg"):
        raise InputError("--output", f"with --at, a .png or .svg file (got {out.name})")
    try:
        if not book.is_file():
            raise AnimationError(f"{book}: no such file")
        anim = frame_at(book, args.at)
        if not anim.drawn:
            raise AnimationError(f"{book}: the loop cannot close at {anim.symbol} = {args.at:g}")
        if kind == "svg":
            write_atomic(out, lambda tmp: write_svg(anim, tmp, args.size))
        else:
            image = render(anim, args.size)[0]
            write_atomic(out, lambda tmp: image.save(tmp, format="PNG"))
    except OSError as exc:
        print(f"linkbook: error: cannot write {out}: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except (AnimationError, UnsafeFile) as exc:
        print(f"linkbook: error: {exc}", file=sys.stderr)
        return 2
    print(f"wrote {out}: the mechanism at {anim.symbol} = {args.at:g} {anim.unit}".rstrip())
    return 0


def _preview(args) -> int:
    from .office import OfficeUnavailable, preview, visible_sheets
    from .safety import UnsafeFile, check_zip
    book = Path(args.book)
    try:
        check_zip(book)
        sheets = _chosen_sheets(book, args.sheet, visible_sheets(book))
        outdir = Path(args.outdir) if args.outdir else book.with_name(book.stem + "_preview")
        outdir.mkdir(parents=True, exist_ok=True)
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
    for path in templates.bundled():
        t = templates.load(str(path))
        steps = ", ".join(dict.fromkeys(s["type"] for s in t.mechanism.description["steps"]))
        print(f"{t.name:24} {t.title}  [{steps}]")
        if verbose:
            for p in t.parameters:
                print(f"    {p.symbol:12} = {p.value:<10g} {p.unit:4} {p.label}")
    return 0


def _build(args) -> int:
    if args.all:
        if args.template or args.output or args.assignments or args.step or args.branch \
                or args.unit:
            raise InputError("--all", "builds the bundled templates as they are; give no "
                                      "template, -o, --set, --step, --branch or --unit with it")
        outdir = Path(args.outdir or "output")
        outdir.mkdir(parents=True, exist_ok=True)
        from .builder import build_file
        for path in templates.bundled():
            t = templates.load(str(path))
            out = outdir / f"{t.name}.xlsx"
            build_file(t, out, args.values)
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
    out = Path(args.output or f"{t.name}.xlsx")
    if out.suffix.lower() != ".xlsx":
        raise InputError("-o", f"must name an .xlsx file (got {str(out)!r})")
    if not out.parent.is_dir():
        raise InputError("-o", f"folder {str(out.parent)!r} does not exist")
    from .builder import build_file
    build_file(t, out, args.values)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    run()
