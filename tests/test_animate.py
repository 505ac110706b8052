"""`linkbook animate`, and engine.vary that computes its frames.

Frames are the book's own drawing data evaluated with the input cell set: checked here against
a full evaluation of the book (bit for bit) and against the independent reference (the joints),
also for a book whose inputs were edited after it was built.
"""
from __future__ import annotations

import math
import zipfile
from pathlib import Path

import numpy as np
import openpyxl
import pytest
from conftest import template
from PIL import Image

from linkbook.book import builder
from linkbook.apps import cli
from linkbook.engine import evaluator as engine
from linkbook.check import verifier
from linkbook.base.sheets import read_meta, read_record
from linkbook.apps.animate import AnimationError, frame_at, frames_of, render, write_mp4

BUNDLED = sorted(p.stem for p in Path(__file__).resolve().parents[1].glob("templates/*.toml"))
NON_GRASHOF = ("a1=100", "a2=60", "a3=50", "a4=40")


@pytest.fixture(scope="module")
def books(bundled_books, tmp_path_factory) -> dict[str, Path]:
    """Every bundled book (conftest's, built once for the run: read only here) and a
    non-Grashof four-bar."""
    path = tmp_path_factory.mktemp("books") / "non-grashof.xlsx"
    builder.build_file(template("fourbar", NON_GRASHOF), path)
    return {**bundled_books, "non-grashof": path}


def _same(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and (a == b or str(a) == str(b))


@pytest.mark.parametrize("name", ["fourbar", "pump", "boom-cylinder"])
def test_vary_equals_a_full_evaluation(books, name):
    """Every formula cell, for several input values, as evaluate() gives it with the input cell
    set: the batched re-evaluation of the downstream groups changes no bit."""
    wb = openpyxl.load_workbook(books[name])
    cells = [(ws.title, c.coordinate) for ws in wb.worksheets for row in ws.iter_rows()
             for c in row if c.data_type == "f"]
    sweep = wb["Sweep"]
    inputs = [sweep["A5"].value, sweep["A6"].value + 0.25, sweep["A9"].value]
    got = list(engine.vary(wb, ("Mechanism", "I7"), inputs, cells + [("Nowhere", "A1")]))
    for value, frame in zip(inputs, got):
        assert frame[("Nowhere", "A1")] is None
        wb["Mechanism"]["I7"] = value
        full = engine.evaluate(wb)
        bad = [k for k in cells if not _same(full[k], frame[k])]
        assert not bad, f"{value}: {bad[:5]}"


def test_vary_refuses_a_formula_input(books):
    wb = openpyxl.load_workbook(books["fourbar"])
    with pytest.raises(engine.EngineError, match="holds a formula"):
        list(engine.vary(wb, ("Mechanism", "I8"), [1.0], [("Mechanism", "N9")]))


def _reference_joints(path: Path, angles) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    wb = openpyxl.load_workbook(path)
    record = read_record(wb)
    ref = verifier.Reference(record).solve(verifier.inputs_of(wb, record),
                                           np.asarray(angles, float))
    return ref["points"], np.asarray(ref["assembled"], dtype=bool)


def test_an_edited_book_animates_as_edited(books, tmp_path):
    """The crank made 25 mm and the coupler point moved in the workbook itself: every frame's
    joints are the reference's for the edited inputs."""
    edited = tmp_path / "edited.xlsx"
    wb = openpyxl.load_workbook(books["fourbar"])
    meta = read_meta(wb)
    wb["Mechanism"][meta["inputs"]["a2"]["cell"]] = 25.0
    wb["Mechanism"][meta["inputs"]["b3"]["cell"]] = 90.0
    wb.save(edited)
    anim = frames_of(edited)
    angles = [f.value for f in anim.frames]
    assert angles == [5.0 * k for k in range(72)]
    points, assembled = _reference_joints(edited, angles)
    assert assembled.all() and all(f.links is not None for f in anim.frames)
    for k, frame in enumerate(anim.frames):
        for name, (x, y) in frame.points.items():
            assert x == pytest.approx(points[name][0][k], abs=1e-9 * 200)
            assert y == pytest.approx(points[name][1][k], abs=1e-9 * 200)
        assert math.dist(frame.points["A0"], frame.points["A"]) == pytest.approx(25.0)
        # the links are drawn through the joints they name (link 1, the ground, comes first)
        assert frame.links[0] == [frame.points["A0"], frame.points["B0"]]
        assert frame.links[1] == [frame.points["A0"], frame.points["A"]]


def test_rows_that_cannot_close_are_left_out(books):
    anim = frames_of(books["non-grashof"])
    _, assembled = _reference_joints(books["non-grashof"], [f.value for f in anim.frames])
    assert [f.links is not None for f in anim.frames] == assembled.tolist()
    assert 0 < len(anim.drawn) < len(anim.frames)
    images = render(anim, 200)
    assert anim.whole_turn and len(images) == len(anim.drawn)


def test_step_sets_the_frames(books):
    anim = frames_of(books["fourbar"], step=7.5)
    assert [f.value for f in anim.frames] == [7.5 * k for k in range(48)]


@pytest.mark.parametrize("name", BUNDLED)
def test_every_bundled_book_animates(books, tmp_path, name, capsys):
    out = tmp_path / f"{name}.gif"
    assert cli.main(["animate", str(books[name]), "-o", str(out), "--size", "240"]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    wb = openpyxl.load_workbook(books[name], read_only=True)   # only the Sweep sheet is read
    column = [v for (v,) in wb["Sweep"].iter_rows(min_row=5, max_col=1, values_only=True)
              if isinstance(v, (int, float))]
    wb.close()
    whole_turn = math.isclose(column[-1] - column[0], 360.0)
    with Image.open(out) as gif:
        assert gif.size == (240, 240)
        # a whole turn loops as it is (its last value is its first); a stroke plays and back
        assert gif.n_frames == (len(column) - 1 if whole_turn else 2 * len(column) - 2)
        gif.seek(0)
        first = gif.convert("RGB").tobytes()
        gif.seek(gif.n_frames // 2)
        assert gif.convert("RGB").tobytes() != first, "the mechanism does not move"


def test_mp4(needs, books, tmp_path):
    needs("ffmpeg")
    out = tmp_path / "fourbar.mp4"
    assert cli.main(["animate", str(books["fourbar"]), "-o", str(out), "--size", "200",
                     "--step", "30"]) == 0
    head = out.read_bytes()[:12]
    assert head[4:8] == b"ftyp" and out.stat().st_size > 1000


def test_mp4_without_the_encoder_says_how_to_get_it(monkeypatch, tmp_path):
    import builtins
    real_import = builtins.__import__

    def no_ffmpeg(name, *args, **kwargs):
        if name == "imageio_ffmpeg":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no_ffmpeg)
    with pytest.raises(AnimationError, match=r"pip install 'linkbook\[video\]'"):
        write_mp4([Image.new("RGB", (10, 10))], tmp_path / "x.mp4", 10)


@pytest.mark.parametrize("argv, message", [
    (["-o", "x.png"], "--output: a .gif or .mp4 file"),
    (["--step", "0.0001"], "frames (at most"),
])
def test_bad_requests_are_one_line(books, tmp_path, capsys, argv, message):
    assert cli.main(["animate", str(books["fourbar"])] + argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


@pytest.mark.parametrize("argv", [["--size", "50"], ["--fps", "0"], ["--step", "-5"],
                                  ["--step", "nan"], ["--at", "nan"], ["--at", "x"]])
def test_bad_options_exit_2(books, argv, capsys):
    with pytest.raises(SystemExit) as stop:
        cli.main(["animate", str(books["fourbar"])] + argv)
    assert stop.value.code == 2


def test_not_a_book(tmp_path, capsys):
    plain = tmp_path / "plain.xlsx"
    openpyxl.Workbook().save(plain)
    junk = tmp_path / "junk.xlsx"
    junk.write_text("not a zip")
    for path in (plain, junk, tmp_path / "missing.xlsx"):
        assert cli.main(["animate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("linkbook: error:") == 3 and "Traceback" not in err
    assert not zipfile.is_zipfile(junk)


def test_a_sweep_with_a_shorter_last_step_still_loops(tmp_path):
    path = tmp_path / "s25.xlsx"
    builder.build_file(template("fourbar", step=25), path)
    anim = frames_of(path)
    assert anim.whole_turn and [f.value for f in anim.frames][-2:] == [325.0, 350.0]


def test_an_odd_size_makes_a_gif_and_is_refused_for_an_mp4_naming_it(books, tmp_path, capsys):
    """Only an MP4's frames are made of 2 × 2 blocks: a GIF takes any size, and the refusal of
    an odd MP4 names the .mp4, not "video frames" of a GIF."""
    gif = tmp_path / "odd.gif"
    assert cli.main(["animate", str(books["fourbar"]), "-o", str(gif), "--size", "601",
                     "--step", "90"]) == 0
    with Image.open(gif) as im:
        assert im.size == (601, 601)
    capsys.readouterr()
    assert cli.main(["animate", str(books["fourbar"]), "-o", str(tmp_path / "odd.mp4"),
                     "--size", "601"]) == 2
    err = capsys.readouterr().err
    assert "--size: must be even for an .mp4 (got 601)" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "odd.mp4").exists()


def test_at_is_the_frame_of_that_input(books):
    """--at evaluates the book's drawing at one value: the very frame the sweep has there."""
    one = frame_at(books["slider-crank"], 60.0)
    sweep = frames_of(books["slider-crank"])
    assert len(one.frames) == 1
    assert one.frames[0].links == next(f.links for f in sweep.frames if f.value == 60.0)
    assert one.fixed == ["A0"]       # the sweep's joints that never move, not all of them


def test_at_writes_a_png_and_an_svg_with_the_guide_and_block(books, tmp_path, capsys):
    import xml.etree.ElementTree as ET
    png, svg = tmp_path / "pos.png", tmp_path / "pos.svg"
    for out in (png, svg):
        assert cli.main(["animate", str(books["slider-crank"]), "--at", "60", "-o", str(out),
                         "--size", "300"]) == 0
        assert f"wrote {out}: the mechanism at θ12 = 60" in capsys.readouterr().out
    with Image.open(png) as im:
        assert im.size == (300, 300) and im.format == "PNG"
    ns = {"s": "http://www.w3.org/2000/svg"}
    root = ET.parse(svg).getroot()
    polygons = root.findall("s:polygon", ns)
    assert len(polygons) == 1 and len(polygons[0].get("points").split()) == 5   # the block
    lines = root.findall("s:polyline", ns)
    assert len(lines) == 3            # the guide, link 2, link 3
    assert any("θ12 = 60°" in (t.text or "") for t in root.findall("s:text", ns))


@pytest.mark.parametrize("argv, message", [
    (["--at", "60", "-o", "x.gif"], "--output: with --at, a .png or .svg file"),
    (["--at", "130"], "the loop cannot close at θ12 = 130"),
])
def test_bad_pictures_are_one_line(books, tmp_path, capsys, argv, message):
    assert cli.main(["animate", str(books["non-grashof"])] + argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err
