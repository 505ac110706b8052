"""The README's Python examples run as written: each ```python block of README.md, in a fresh
folder, in a process of its own (the CI block with books that agree, disagree and cannot be
verified; the plot of T12 with matplotlib, or where it is not installed with a stand-in that
records what was drawn), and the messages it quotes are the ones the API raises."""
from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import json

import openpyxl
import pytest

from conftest import HANG_GUARD_S, ROOT
from linkbook.base.sheets import read_meta
from linkbook.engine import evaluator as engine

README = (ROOT / "README.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", README, flags=re.S)


STUBS = ROOT / "tests" / "readme_stubs"


def _run_block(code: str, cwd: Path, *paths: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(map(str, [ROOT / "src", *paths])),
               MPLBACKEND="Agg")
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=HANG_GUARD_S)


def _block_with(text: str) -> str:
    [block] = [b for b in BLOCKS if text in b]
    return block


def test_the_readme_has_the_api_the_tables_and_the_ci_blocks():
    assert len(BLOCKS) == 3, BLOCKS
    for text in ("report = linkbook.verify(", "linkbook.tables(", "sys.exit("):
        _block_with(text)


def _has_matplotlib() -> bool:
    import importlib.util
    return importlib.util.find_spec("matplotlib") is not None


def test_the_tables_example_plots_t12(tmp_path):
    """The T12 column of the Forces sheet against θ12, as the engine computes the book's cells
    (a NaN where the book shows #N/A), into T12.png."""
    real = _has_matplotlib()
    done = _run_block(_block_with("linkbook.tables("), tmp_path, *([] if real else [STUBS]))
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["T12.png", "fourbar.xlsx"]
    if real:
        assert (tmp_path / "T12.png").read_bytes().startswith(b"\x89PNG")
        return
    drawn = json.loads((tmp_path / "T12.png").read_text(encoding="utf-8"))
    values = engine.evaluate_file(tmp_path / "fourbar.xlsx")
    forces = read_meta(openpyxl.load_workbook(tmp_path / "fourbar.xlsx"))["forces"]
    rows = range(forces["rows"][0], forces["rows"][1] + 1)

    def column(letter):
        cells = (values[("Forces", f"{letter}{r}")] for r in rows)
        return [None if engine.is_error(v) else v for v in cells]
    [line] = drawn["lines"]
    assert line["x"] == column("A")
    assert line["y"] == column(forces["columns"]["T12"]) and len(line["y"]) > 10
    assert (drawn["xlabel"], drawn["ylabel"]) == ("θ12 [deg]", "T12 [N·m]")


def test_the_api_example_runs_as_written(tmp_path):
    done = _run_block(_block_with("report = linkbook.verify("), tmp_path)
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fourbar.xlsx"]


@pytest.fixture(scope="module")
def good_book(coarse_fourbar) -> bytes:
    return coarse_fourbar.read_bytes()


@pytest.mark.parametrize("others,status", [((), 0), (("disagrees",), 1),
                                           (("disagrees", "junk"), 2), (("junk",), 2)])
def test_the_ci_example_exits_with_the_worst_status(tmp_path, good_book, others, status):
    books = tmp_path / "books"
    books.mkdir()
    (books / "good.xlsx").write_bytes(good_book)
    if "disagrees" in others:
        (books / "edited.xlsx").write_bytes(good_book)
        wb = openpyxl.load_workbook(books / "edited.xlsx")
        wb["Sweep"]["H10"].value += "*1.001"
        wb.save(books / "edited.xlsx")
    if "junk" in others:
        (books / "junk.xlsx").write_text("not a workbook")
    done = _run_block(_block_with("sys.exit("), tmp_path)
    assert done.returncode == status and "Traceback" not in done.stderr, done.stderr


def test_the_messages_the_readme_quotes_are_the_apis(tmp_path, monkeypatch):
    import linkbook
    monkeypatch.chdir(tmp_path)
    for kwargs in (dict(sets=["a2=-1"]), dict(output="out/fourbar.xlsx")):
        with pytest.raises(linkbook.InputError) as caught:
            linkbook.build("fourbar", **kwargs)
        assert f"`{caught.value}`" in README, str(caught.value)
