"""The documented Python API (README "Python API"): linkbook.build and linkbook.verify."""
from __future__ import annotations

import openpyxl
import pytest

import linkbook


def test_build_then_verify(tmp_path):
    path = linkbook.build("slider-crank", tmp_path / "sc.xlsx", sets=["a2=45"], step=30)
    assert path == tmp_path / "sc.xlsx" and path.is_file()
    report = linkbook.verify(path)
    assert report.status == 0 and report.ok and report.differing == 0 and not report.causes
    assert report.cells == report.formula_cells > 100
    assert report.inputs["a2"] == 45.0


def test_a_broken_book_reports_its_cause(tmp_path):
    path = linkbook.build("slider-crank", tmp_path / "sc.xlsx", step=30)
    wb = openpyxl.load_workbook(path)
    cell = wb["Mechanism"]["I9"]            # the input angle's radian cell
    assert isinstance(cell.value, str) and cell.value.startswith("=")
    cell.value += "+0.001"
    wb.save(path)
    report = linkbook.verify(path)
    assert report.status == 1 and report.differing >= 1
    assert report.causes == {("Mechanism", "I9")}


def test_bad_input_raises_one_line_errors(tmp_path):
    with pytest.raises(linkbook.InputError) as caught:
        linkbook.build("fourbar", tmp_path / "x.xlsx", sets=["a2=-1"])
    assert "a2" in str(caught.value) and "\n" not in str(caught.value)
    assert not (tmp_path / "x.xlsx").exists()
    with pytest.raises(linkbook.InputError):
        linkbook.build("fourbar", tmp_path / "x.txt")
    (tmp_path / "not.xlsx").write_bytes(b"no zip")
    with pytest.raises(linkbook.UnusableFile):
        linkbook.verify(tmp_path / "not.xlsx")


def test_aggregate_is_known_even_when_formulas_made_its_table_first(tmp_path):
    """formulas' get_functions() copies its table once; AGGREGATE must be in that copy too."""
    import subprocess
    import sys
    code = ("from formulas.functions import get_functions; get_functions()\n"
            "import linkbook\n"
            f"p = linkbook.build('fourbar', {str(tmp_path / 'f.xlsx')!r}, step=30)\n"
            "raise SystemExit(linkbook.verify(p).status)")
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_the_garbage_collector_is_paused_only_during_a_call(tmp_path):
    """build and verify pause Python's cyclic collector (linkbook.pause) and give it back as
    they found it: on after a call that returns or raises, off if it was off."""
    import gc
    seen = []
    real_verify = linkbook.verifier.verify.__wrapped__

    def spy(*args, **kwargs):
        seen.append(gc.isenabled())
        return real_verify(*args, **kwargs)

    path = linkbook.build("slider-crank", tmp_path / "sc.xlsx", step=30)
    assert gc.isenabled()
    paused = linkbook.pause.gc_paused(spy)
    assert paused(path).status == 0 and seen == [False] and gc.isenabled()
    with pytest.raises(linkbook.UnusableFile):
        paused(tmp_path / "missing.xlsx")
    assert seen == [False, False] and gc.isenabled()
    gc.disable()
    try:
        paused(path)
        assert seen[-1] is False and not gc.isenabled()
    finally:
        gc.enable()
