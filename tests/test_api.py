"""The documented Python API (README "Python API"): linkbook.build, linkbook.verify and
linkbook.tables (its numbers: tests/test_export.py)."""
from __future__ import annotations

import openpyxl
import pytest

import linkbook
import linkbook.base.pause
import linkbook.check.verifier


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
    report = linkbook.verify(tmp_path / "not.xlsx")
    assert report.status == 2 and not report.ok and "not a zip" in report.error
    assert "\n" not in report.error


API_MISTAKES = [
    # (what, build's arguments, the start of the one line it raises)
    ("sets as one text", dict(sets="a2=40"), "sets: must be a list of KEY=VALUE texts"),
    ("an assignment without =", dict(sets=["a2"]), "sets: expects KEY=VALUE (got 'a2')"),
    ("an assignment that is not text", dict(sets=[("a2", 40)]), "sets: expects KEY=VALUE"),
    ("a bad value", dict(sets=["a2=-1"]), "sets a2: must be a positive length"),
    ("an unknown key", dict(sets=["a9=1"]), "sets a9: unknown parameter"),
    ("a bad step", dict(step="x"), "step: must be a number"),
    ("a bad branch", dict(branch="sideways"), "branch: must be open or crossed"),
    ("a bad unit", dict(unit="furlong"), "unit: must be one of"),
    ("a missing folder", dict(output="out/fourbar.xlsx"), "output: folder 'out' does not exist"),
    ("a folder for the file", dict(output="."), "output: '.' is a folder"),
]


@pytest.mark.parametrize("what,kwargs,starts", API_MISTAKES, ids=[m[0] for m in API_MISTAKES])
def test_the_api_names_its_own_arguments_never_a_flag(tmp_path, monkeypatch, what, kwargs,
                                                      starts):
    """The API's messages name build's arguments (sets, step, output), not the command line's
    flags (--set, -o), and no file is left behind."""
    monkeypatch.chdir(tmp_path)
    kwargs.setdefault("output", "fourbar.xlsx")
    with pytest.raises(linkbook.InputError) as caught:
        linkbook.build("fourbar", **kwargs)
    text = str(caught.value)
    assert text.startswith(starts) and "--" not in text and "\n" not in text, text
    assert list(tmp_path.iterdir()) == []


def test_the_error_types_are_part_of_the_module():
    """dir(linkbook) and __all__ show the exceptions the API raises (they load on first use)."""
    for name in ("InputError", "UnusableFile", "CannotWrite"):
        assert name in dir(linkbook) and name in linkbook.__all__
        assert issubclass(getattr(linkbook, name), Exception)
    assert issubclass(linkbook.CannotWrite, OSError)


def test_tables_is_part_of_the_module_and_loads_nothing_on_import():
    """`import linkbook` stays light (the command line's start-up): numpy and the readers load
    when tables is called."""
    import subprocess
    import sys
    code = ("import sys, linkbook\n"
            "assert 'tables' in dir(linkbook) and 'tables' in linkbook.__all__\n"
            "assert callable(linkbook.tables)\n"
            "print(sorted(m for m in ('numpy', 'openpyxl', 'linkbook.apps.export') "
            "if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == "[]", done.stderr


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
    """build and verify pause Python's cyclic collector (linkbook.base.pause) and give it back as
    they found it: on after a call that returns or raises, off if it was off."""
    import gc
    seen = []
    real_verify = linkbook.check.verifier.verify.__wrapped__

    def spy(*args, **kwargs):
        seen.append(gc.isenabled())
        return real_verify(*args, **kwargs)

    path = linkbook.build("slider-crank", tmp_path / "sc.xlsx", step=30)
    assert gc.isenabled()
    paused = linkbook.base.pause.gc_paused(spy)
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


def test_a_refused_write_raises_cannot_write_naming_the_target(tmp_path, monkeypatch):
    """A full disk is the environment's doing: CannotWrite, an OSError with the original errno,
    one line naming the target (not the hidden temporary file); nothing left behind."""
    import errno
    import os

    from linkbook.book import package

    def full(src, dst, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(dst))
    monkeypatch.setattr(package, "finish", full)
    target = tmp_path / "sc.xlsx"
    with pytest.raises(linkbook.CannotWrite) as caught:
        linkbook.build("slider-crank", target, step=30)
    assert caught.value.errno == errno.ENOSPC and isinstance(caught.value, OSError)
    assert str(caught.value) == f"cannot write {target}: the disk is full"
    assert list(tmp_path.iterdir()) == []
