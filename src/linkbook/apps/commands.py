"""The commands but verify (verdict.py): list, new, check, build, info, export, animate and
preview. Each takes the parsed arguments and returns the exit status; each imports what it
needs when it runs."""
from __future__ import annotations

import sys
from pathlib import Path

from ..base.errors import InputError
from .lines import error, notes, warn

def summarise(args) -> int:
    import json
    from . import info
    from ..check.verifier import UnusableFile
    try:
        book = (info.open_book(Path(args.book)) if args.book.lower().endswith(".xlsx")
                else info.built_book(args.book))
        data = info.read_record(book, info.summary)
    except UnusableFile as exc:
        error(exc)
        return 2
    notes(book.name, getattr(book.wb, "notes", ()))
    print(json.dumps(data, indent=2, ensure_ascii=False) if args.json
          else "\n".join(info.lines(data)))
    return 0


def export_tables(args) -> int:
    from .export import export, table_texts
    from ..base.files import ensure_folder
    from .info import open_book, read_record
    from ..check.verifier import UnusableFile
    book = Path(args.book)
    try:
        opened = open_book(book)
        texts = read_record(opened, table_texts)
    except UnusableFile as exc:
        error(exc)
        return 2
    notes(book, getattr(opened.wb, "notes", ()))
    outdir = ensure_folder(Path(args.outdir) if args.outdir
                           else book.with_name(book.stem + "_csv"), "--outdir")
    for path in export(texts, book.stem, outdir):
        print(f"wrote {path}")
    return 0


def animate(args) -> int:
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


def preview_pages(args) -> int:
    from ..base.files import ensure_folder
    from ..engine.errors import OfficeUnavailable
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


def list_templates(args) -> int:
    from ..language import templates
    for path in templates.bundled():
        t = templates.load(str(path))
        steps = ", ".join(dict.fromkeys(s["type"] for s in t.mechanism.description["steps"]))
        print(f"{t.name:24} {t.title}  [{steps}]")
        if args.verbose:
            for p in t.parameters:
                made = f" (designed by {p.designed_by})" if p.designed_by else ""
                print(f"    {p.symbol:12} = {p.value:<10g} {p.unit:4} {p.label}{made}")
    return 0


def copy_template(args) -> int:
    from ..language import templates
    out = templates.copy_bundled(args.template, Path(args.output))
    print(f"wrote {out}: the bundled {args.template}; edit it, then `linkbook check {out}` "
          f"and `linkbook build {out}`")
    return 0


def check_template(args) -> int:
    from ..book.builder import make
    from ..language import templates
    t = templates.load(args.template)
    built, _ = make(t, values_needed=False)
    warn(built)
    print(f"{args.template}: ok ({len(t.mechanism.description['steps'])} steps, "
          f"{len(t.parameters)} parameters)")
    return 0


def build(args) -> int:
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
            warn(build_file(t, out, args.values))
            print(f"wrote {out}")
        return 0
    if not args.template:
        raise InputError("build", "give a template name or .toml file, or --all")
    if args.outdir:
        raise InputError("--outdir", "goes with --all; use -o for one workbook")
    from ..book.builder import build_template
    # an empty -o or --unit is as if not given
    out, built = build_template(args.template, args.output or None, sets=args.assignments,
                                step=args.step, branch=args.branch, unit=args.unit or None,
                                values=args.values)
    warn(built)
    print(f"wrote {out}")
    return 0
