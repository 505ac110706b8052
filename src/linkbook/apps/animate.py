"""`linkbook animate`: the mechanism drawing over the whole sweep, as a GIF.

Every frame is what the workbook's own drawing shows when its input cell (the one the spin
button moves) holds that frame's value: the book's formulas are evaluated by the fast engine
with the input cell set, and the links are read from the drawing data the chart plots. So a book
edited in Excel animates as edited. Only the cells downstream of the input cell are evaluated
again, all frame values at once (engine.vary).

Frames where the drawing data is not a number (#N/A: the loop cannot close there) are left out,
and a note on every frame says how many were.
"""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

from ..engine import evaluator as engine
from ..base import sheets as layout
from ..base.palette import PATH_COLOUR, drawing_colours, nice_step
from ..base.record import BuildRecord, DamagedRecord, Position, Sweep

DEFAULT_FPS = 20
DEFAULT_SIZE = 600
MAX_FRAMES = 3600
MAX_SIZE = 4000


class AnimationError(Exception):
    """The book cannot be animated (said in one line)."""


@dataclass
class Frame:
    """One frame of the animation: the input's value and the links drawn there."""
    value: float                                       # the input (degrees or length)
    links: list[list[tuple[float, float]]] | None      # None: the loop cannot close here
    points: dict[str, tuple[float, float]] = field(default_factory=dict)


@dataclass
class Animation:
    """What the animation draws: its frames, the links' names and colours, the traced point."""
    title: str
    symbol: str                   # θ12, s
    unit: str                     # deg or the length unit
    length_unit: str
    link_names: list[str]
    traced: str | None
    frames: list[Frame]
    whole_turn: bool = True       # else the GIF plays forward, then back
    link_colours: list[str] = field(default_factory=list)   # hex, one per link (the chart's)
    link_kinds: list[str] = field(default_factory=list)     # "link", or a slider's "guide",
                                                            # "slot" or "block"
    fixed: list[str] | None = None    # the joints that never move over the sweep


    @property
    def drawn(self) -> list[Frame]:
        return [f for f in self.frames if f.links is not None]


def frames_of(path: Path, step: float | None = None, at: float | None = None) -> Animation:
    """Evaluate the book at every input value of its sweep (or from the sweep's start to its end
    by `step`, or at the one value `at`) and read the drawing data of each."""
    from ..base.safety import load_workbook_safely
    wb = load_workbook_safely(path)
    try:
        record = layout.read_record(wb)
        if record is None:
            raise AnimationError(f"{path}: not a linkbook workbook (no build record sheet)")
        return _frames(path, wb, record, step, at)
    except DamagedRecord as exc:
        raise AnimationError(f"{path}: the build record (sheet {layout.META}) is damaged: it "
                             f"is {exc}") from None
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        raise AnimationError(f"{path}: the build record (sheet {layout.META}) does not match "
                             f"the workbook ({type(exc).__name__}: {exc})") from None


def frame_at(path: Path, value: float) -> Animation:
    """The book's drawing at one input value: an Animation of one frame."""
    return frames_of(path, at=value)


def _frames(path: Path, wb, record: BuildRecord, step: float | None, at: float | None = None
            ) -> Animation:
    pos, sweep = record.position, record.sweep
    sheet, cell = pos.sheet, pos.input_cell
    if sheet not in wb.sheetnames:
        raise AnimationError(f"{path}: the sheet {sheet!r} is missing")
    column = _sweep_column(wb, sweep)
    inputs = _input_values(column, step, _input_label(wb, sheet, cell, record)[1] == "deg")
    if at is not None:      # the sweep too: which joints never move (the pivots to mark)
        inputs = [at, *inputs]
    x_col, y_col = layout.DRAWING_COLUMNS
    read = [(sheet, f"{col}{r}") for link in pos.drawing for r in range(link.rows[0],
                                                                      link.rows[1] + 1)
            for col in (x_col, y_col)] + [(sheet, c) for xy in pos.joints.values() for c in xy]
    try:
        frames = [_frame(now, sheet, pos, value)
                  for value, now in zip(inputs, engine.vary(wb, (sheet, cell), inputs, read))]
    except engine.EngineError as exc:
        raise AnimationError(f"{path}: {exc}") from None
    symbol, unit = _input_label(wb, sheet, cell, record)
    # a whole turn loops: by --step, or the sweep's own rows over 360° (its last step may be
    # shorter, when the step does not divide the turn)
    whole_turn = at is None and unit == "deg" and (
        abs(inputs[-1] + (inputs[1] - inputs[0]) - inputs[0] - 360.0) < 1e-9
        or (step is None and len(inputs) > 1 and abs(column[-1] - column[0] - 360.0) < 1e-9))
    fixed = _fixed_points([f for f in frames if f.links is not None] or frames)
    return Animation(record.title, symbol, unit, record.length_unit,
                     [link.label for link in pos.drawing], pos.traced,
                     frames[:1] if at is not None else frames, whole_turn=whole_turn,
                     link_colours=drawing_colours([link.to_json() for link in pos.drawing]),
                     link_kinds=[link.kind or "link" for link in pos.drawing], fixed=fixed)


def _sweep_column(wb, sweep: Sweep) -> list[float]:
    """The Sweep sheet's input column as the book holds it now (numbers only)."""
    if sweep.sheet not in wb.sheetnames:
        raise AnimationError(f"the sheet {sweep.sheet!r} is missing")
    ws = wb[sweep.sheet]
    first, last = sweep.rows
    column = [ws[f"A{r}"].value for r in range(first, last + 1)]
    return [float(v) for v in column if _number(v)]


def _input_values(column: list[float], step: float | None, is_angle: bool = True) -> list[float]:
    """The sweep's own input values, or its range by `step`. A whole turn leaves out its last
    value, the first one again, so that the GIF loops smoothly."""
    if len(column) < 2 or column[-1] <= column[0]:
        raise AnimationError("the Sweep sheet's input column must hold two or more numbers, "
                             "rising")
    start, stop = column[0], column[-1]
    if step is not None:
        count = int(math.floor((stop - start) / step + 1e-9)) + 1
        if count > MAX_FRAMES:
            raise AnimationError(f"--step {step:g} makes {count} frames (at most {MAX_FRAMES})")
        if count < 2:
            raise AnimationError(f"--step {step:g} is larger than the sweep "
                                 f"({start:g} to {stop:g}): one frame")
        column = [start + i * step for i in range(count)]
    if is_angle and abs((column[-1] - column[0]) - 360.0) < 1e-9 and len(column) > 2:
        column = column[:-1]
    return column


def _frame(values: dict, sheet: str, pos: Position, value: float) -> Frame:
    x_col, y_col = layout.DRAWING_COLUMNS
    links = []
    for link in pos.drawing:
        r0, r1 = link.rows
        xy = [(values.get((sheet, f"{x_col}{r}")), values.get((sheet, f"{y_col}{r}")))
              for r in range(r0, r1 + 1)]
        if not all(_number(x) and _number(y) for x, y in xy):
            return Frame(value, None)
        links.append([(float(x), float(y)) for x, y in xy])
    points = {}
    for name, (cx, cy) in pos.joints.items():
        x, y = values.get((sheet, cx)), values.get((sheet, cy))
        if _number(x) and _number(y):
            points[name] = (float(x), float(y))
    return Frame(value, links, points)


def _number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _input_label(wb, sheet: str, cell: str, record: BuildRecord) -> tuple[str, str]:
    """The input's symbol and unit as the book labels them (the cells beside the input)."""
    ws = wb[sheet]
    row = int("".join(ch for ch in cell if ch.isdigit()))
    symbol = ws[f"H{row}"].value
    unit = ws[f"J{row}"].value
    return (symbol if isinstance(symbol, str) else record.input,
            unit if isinstance(unit, str) else "")


# ---------------------------------------------------------------- drawing
class _View:
    """Model coordinates to pixels: equal scales on x and y, y up."""

    def __init__(self, frames: list[Frame], box: tuple[int, int, int, int]):
        xs = [x for f in frames for link in f.links for x, _ in link]
        ys = [y for f in frames for link in f.links for _, y in link]
        left, top, right, bottom = box
        span = max(max(xs) - min(xs), max(ys) - min(ys), 1e-12) * 1.08
        self.scale = min(right - left, bottom - top) / span
        self.cx, self.cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
        self.px, self.py = (left + right) / 2, (top + bottom) / 2
        self.box = box
        self.lo_x, self.hi_x = self.cx - (right - left) / 2 / self.scale, \
            self.cx + (right - left) / 2 / self.scale
        self.lo_y, self.hi_y = self.cy - (bottom - top) / 2 / self.scale, \
            self.cy + (bottom - top) / 2 / self.scale

    def __call__(self, x: float, y: float) -> tuple[float, float]:
        return self.px + (x - self.cx) * self.scale, self.py - (y - self.cy) * self.scale


def _tick(v: float, step: float) -> str:
    decimals = max(0, -int(math.floor(math.log10(step))))
    return f"{v:.{decimals}f}" if decimals else f"{v:.0f}"


def render(anim: Animation, size: int = DEFAULT_SIZE, progress=None) -> list:
    """One RGB image per drawn frame (and, unless the input makes a whole turn, the same frames
    again backwards, so that the loop has no jump)."""
    from PIL import Image, ImageDraw, ImageFont
    drawn = anim.drawn
    if not drawn:
        raise AnimationError("the loop cannot close at any input value: nothing to draw")
    font = _font(ImageFont, max(11, size // 45))
    small = _font(ImageFont, max(10, size // 55))
    margin_l, margin_t = int(size * 0.11), int(size * 0.09)
    legend_h = int(size * 0.06) * ((len(anim.link_names) + (1 if anim.traced else 0) + 2) // 3)
    plot = (margin_l, margin_t, size - int(size * 0.04), size - int(size * 0.09) - legend_h)
    view = _View(drawn, plot)
    fixed = anim.fixed if anim.fixed is not None else _fixed_points(drawn)
    skipped = len(anim.frames) - len(drawn)
    background = _background(Image, ImageDraw, anim, view, size, font, small, skipped, legend_h)
    pieces: list[list[tuple[float, float]]] = [[]]    # the path, cut where frames are left out
    images = []
    for frame in anim.frames:
        if frame.links is None:
            if pieces[-1]:
                pieces.append([])
            continue
        im = background.copy()
        d = ImageDraw.Draw(im)
        if anim.traced and anim.traced in frame.points:
            pieces[-1].append(view(*frame.points[anim.traced]))
            for piece in pieces:
                if len(piece) > 1:
                    d.line(piece, fill=PATH_COLOUR_RGB, width=max(1, size // 300))
        _draw_links(d, anim, frame, view, size)
        for name in fixed:
            _ground_mark(d, view(*drawn[0].points[name]), size)
        d.text((plot[0] + 6, plot[1] + 4), f"{anim.symbol} = {_format_input(frame.value, anim.unit)}",
               fill=(0, 0, 0), font=font)
        images.append(im)
        if progress:
            progress(len(images), len(drawn))
    if not anim.whole_turn and len(images) > 2:
        images += images[-2:0:-1]         # an actuator's stroke, or part of a turn: and back
    return images


def _draw_links(d, anim: Animation, frame: Frame, view: _View, size: int) -> None:
    """Guides first, then blocks (filled light, so the links show on them), then the links with
    a dot on each joint."""
    width = max(2, size // 120)
    kinds = anim.link_kinds or ["link"] * len(frame.links)
    order = {"guide": 0, "slot": 0, "block": 1}
    for k in sorted(range(len(frame.links)), key=lambda k: order.get(kinds[k], 2)):
        colour = _rgb(anim.link_colours[k])
        pts = [view(x, y) for x, y in frame.links[k]]
        if kinds[k] in ("guide", "slot"):
            d.line(pts, fill=colour, width=max(1, width // 2))
        elif kinds[k] == "block":
            d.polygon(pts, fill=(225, 225, 225), outline=colour, width=width)
        else:
            d.line(pts, fill=colour, width=width, joint="curve")
            r = width * 1.3
            for px, py in pts:
                d.ellipse((px - r, py - r, px + r, py + r), fill=colour)


def _rgb(hex6: str) -> tuple[int, int, int]:
    return tuple(int(hex6[i:i + 2], 16) for i in (0, 2, 4))


PATH_COLOUR_RGB = _rgb(PATH_COLOUR)


def _format_input(v: float, unit: str) -> str:
    number = f"{v:.0f}" if abs(v - round(v)) < 1e-9 else f"{v:.2f}"
    return f"{number}°" if unit == "deg" else f"{number} {unit}".rstrip()


def _font(ImageFont, px: int):
    for name in ("DejaVuSans.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                 "LiberationSans-Regular.ttf", "Carlito-Regular.ttf"):
        try:
            return ImageFont.truetype(name, px)
        except OSError:
            continue
    return ImageFont.load_default()


def _fixed_points(frames: list[Frame]) -> list[str]:
    """Joints that do not move over the sweep: the fixed pivots."""
    names = set(frames[0].points)
    for f in frames[1:]:
        names &= set(f.points)
    scale = max((abs(c) for f in frames for p in f.points.values() for c in p), default=1.0)
    return sorted(n for n in names
                  if all(math.dist(f.points[n], frames[0].points[n]) <= 1e-9 * scale
                         for f in frames))


def _ground_mark(d, at: tuple[float, float], size: int) -> None:
    """A fixed pivot: a triangle under the joint and a hatched ground line."""
    x, y = at
    h = size / 45
    d.polygon([(x, y), (x - h * 0.7, y + h), (x + h * 0.7, y + h)], outline=(0, 0, 0),
              fill=(235, 235, 235))
    d.line([(x - h, y + h), (x + h, y + h)], fill=(0, 0, 0), width=2)
    for k in range(5):
        sx = x - h + k * h / 2
        d.line([(sx, y + h), (sx - h / 3, y + h * 1.35)], fill=(0, 0, 0), width=1)


def _background(Image, ImageDraw, anim: Animation, view: _View, size: int, font, small,
                skipped: int, legend_h: int):
    im = Image.new("RGB", (size, size), (255, 255, 255))
    d = ImageDraw.Draw(im)
    left, top, right, bottom = view.box
    d.text((size / 2, top * 0.45), anim.title, fill=(0, 0, 0), font=font, anchor="mm")
    step = nice_step(min(view.hi_x - view.lo_x, view.hi_y - view.lo_y))
    for lo, hi, vertical in ((view.lo_x, view.hi_x, True), (view.lo_y, view.hi_y, False)):
        v = math.ceil(lo / step) * step
        while v <= hi + 1e-12 * step:
            if vertical:
                px, _ = view(v, view.cy)
                d.line([(px, top), (px, bottom)], fill=(225, 225, 225))
                d.text((px, bottom + 4), _tick(v, step), fill=(80, 80, 80), font=small,
                       anchor="mt")
            else:
                _, py = view(view.cx, v)
                d.line([(left, py), (right, py)], fill=(225, 225, 225))
                d.text((left - 4, py), _tick(v, step), fill=(80, 80, 80), font=small,
                       anchor="rm")
            v += step
    d.rectangle(view.box, outline=(150, 150, 150))
    unit = anim.length_unit
    d.text(((left + right) / 2, bottom + 6 + small.size), f"x [{unit}]", fill=(0, 0, 0),
           font=small, anchor="mt")
    d.text((4, (top + bottom) / 2), f"y [{unit}]", fill=(0, 0, 0), font=small, anchor="lm")
    entries = [(name, _rgb(colour)) for name, colour in zip(anim.link_names, anim.link_colours)]
    if anim.traced:
        entries.append((f"path of {anim.traced}", PATH_COLOUR_RGB))
    row_h = legend_h / max(1, (len(entries) + 2) // 3)
    y0 = size - legend_h - (size * 0.02)
    for k, (name, colour) in enumerate(entries):
        x = left + (k % 3) * (right - left) / 3
        y = y0 + (k // 3) * row_h + row_h / 2
        d.line([(x, y), (x + 22, y)], fill=colour, width=4)
        d.text((x + 28, y), name, fill=(0, 0, 0), font=small, anchor="lm")
    if skipped:
        d.text((size / 2, top * 0.8), f"{skipped} of {len(anim.frames)} input values left "
                                      "out: the loop cannot close there", fill=(170, 0, 0),
               font=small, anchor="mm")
    return im


def write_svg(anim: Animation, out: Path, size: int = DEFAULT_SIZE) -> None:
    """The first drawn frame as SVG: links, guides and blocks in the book's colours at equal
    scales, joints as dots, the title and the input value; a grid line every nice step."""
    frame = anim.drawn[0] if anim.drawn else None
    if frame is None:
        raise AnimationError("the loop cannot close at this input value: nothing to draw")
    margin = size * 0.08
    view = _View([frame], (margin, margin * 1.4, size - margin, size - margin))
    left, top, right, bottom = view.box
    out_lines = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{size}" height="{size}" '
                 f'viewBox="0 0 {size} {size}" font-family="DejaVu Sans, sans-serif">',
                 f'<rect width="{size}" height="{size}" fill="white"/>']
    step = nice_step(min(view.hi_x - view.lo_x, view.hi_y - view.lo_y))
    for lo, hi, vertical in ((view.lo_x, view.hi_x, True), (view.lo_y, view.hi_y, False)):
        v = math.ceil(lo / step) * step
        while v <= hi + 1e-12 * step:
            p = view(v, v)
            a, b = ((p[0], top), (p[0], bottom)) if vertical else ((left, p[1]), (right, p[1]))
            out_lines.append(f'<line x1="{a[0]:.2f}" y1="{a[1]:.2f}" x2="{b[0]:.2f}" '
                             f'y2="{b[1]:.2f}" stroke="#e1e1e1"/>')
            v += step
    width = max(2, size // 120)
    kinds = anim.link_kinds or ["link"] * len(frame.links)
    order = {"guide": 0, "slot": 0, "block": 1}
    for k in sorted(range(len(frame.links)), key=lambda k: order.get(kinds[k], 2)):
        colour = "#" + anim.link_colours[k]
        pts = " ".join(f"{x:.2f},{y:.2f}" for x, y in (view(*p) for p in frame.links[k]))
        if kinds[k] == "block":
            out_lines.append(f'<polygon points="{pts}" fill="#e1e1e1" stroke="{colour}" '
                             f'stroke-width="{width}"/>')
            continue
        thin = kinds[k] in ("guide", "slot")
        out_lines.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" '
                         f'stroke-width="{max(1, width // 2) if thin else width}" '
                         'stroke-linejoin="round"/>')
        if not thin:
            out_lines += [f'<circle cx="{x:.2f}" cy="{y:.2f}" r="{width * 1.3:.2f}" '
                          f'fill="{colour}"/>' for x, y in (view(*p) for p in frame.links[k])]
    title = f"{anim.title}: {anim.symbol} = {_format_input(frame.value, anim.unit)}"
    out_lines += [f'<rect x="{left}" y="{top}" width="{right - left}" height="{bottom - top}" '
                  'fill="none" stroke="#969696"/>',
                  f'<text x="{size / 2}" y="{margin * 0.8:.2f}" text-anchor="middle" '
                  f'font-size="{max(11, size // 45)}">{_xml_text(title)}</text>',
                  f'<text x="{right}" y="{size - margin * 0.4:.2f}" text-anchor="end" '
                  f'font-size="{max(10, size // 55)}">grid {_tick(step, step)} '
                  f'{_xml_text(anim.length_unit)}</text>', "</svg>"]
    out.write_text("\n".join(out_lines) + "\n", encoding="utf-8")


def _xml_text(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def write_video(images: list, out: Path, fps: int, kind: str) -> None:
    """A GIF (Pillow), or an H.264 MP4 (the ffmpeg that the imageio-ffmpeg package ships)."""
    if kind == "gif":
        write_gif(images, out, fps)
    else:
        write_mp4(images, out, fps)


def write_mp4(images: list, out: Path, fps: int) -> None:
    try:
        import imageio_ffmpeg
    except ImportError:
        raise AnimationError("writing .mp4 needs the imageio-ffmpeg package: "
                             "pip install 'linkbook[video]' (or write a .gif)") from None
    width, height = images[0].size
    writer = imageio_ffmpeg.write_frames(
        str(out), (width, height), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
        macro_block_size=2, quality=7, output_params=["-f", "mp4", "-movflags", "+faststart"])
    writer.send(None)
    for im in images:
        writer.send(im.tobytes())
    writer.close()


def write_gif(images: list, out: Path, fps: int) -> None:
    """A looping GIF, one palette for all frames (the background's and the links' colours)."""
    from PIL import Image
    palette_source = images[len(images) // 2].quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    frames = [im.quantize(palette=palette_source, dither=Image.Dither.NONE) for im in images]
    frames[0].save(out, save_all=True, append_images=frames[1:], duration=round(1000 / fps),
                   loop=0, optimize=False, disposal=1, format="GIF")


def terminal_progress(stream=sys.stderr):
    """A one-line progress bar on a terminal; nothing when the output is not one."""
    if not stream.isatty():
        return None

    def show(done: int, total: int) -> None:
        width = 30
        filled = round(width * done / total)
        stream.write(f"\r  [{'#' * filled}{'.' * (width - filled)}] {done}/{total} frames")
        if done == total:
            stream.write("\n")
        stream.flush()
    return show
