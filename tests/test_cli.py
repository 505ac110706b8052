"""The command line: list, build, and bad input that exits 2 with one line and writes nothing."""
from __future__ import annotations

import contextlib
import io
import json
import os
import subprocess
import sys

import openpyxl
import pytest

from conftest import HANG_GUARD_S, ROOT
from linkbook.apps.cli import main

ENV_PATH = str(ROOT / "src")


def run(*args, cwd=None) -> subprocess.CompletedProcess:
    """`python -m linkbook ARGS` in a process of its own: for what the process shell (cli.run:
    the exit status, the streams flushed, signals) does."""
    env = dict(os.environ, PYTHONPATH=ENV_PATH)
    env.pop("PYTHONUNBUFFERED", None)   # stdout block-buffered into a pipe, as users have it
    return subprocess.run([sys.executable, "-m", "linkbook", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=HANG_GUARD_S)


def run_in_process(*args, cwd=None) -> subprocess.CompletedProcess:
    """`linkbook ARGS` as `run` gives it (status, stdout, stderr), by cli.main in this process:
    for what a command prints and writes, without a Python start-up and its imports per call.
    The tests of the process shell above and below use `run`."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd or os.getcwd()), contextlib.redirect_stdout(out), \
            contextlib.redirect_stderr(err):
        try:
            status = main(list(args))
        except SystemExit as exc:       # argparse's own exit: a usage error, --help
            status = exc.code
    return subprocess.CompletedProcess(["linkbook", *args], status, out.getvalue(),
                                       err.getvalue())


def test_list_shows_every_bundled_template():
    out = run("list")
    assert out.returncode == 0
    names = [line.split()[0] for line in out.stdout.splitlines()]
    assert names == sorted(["fourbar", "slider-crank", "pump", "inverted-slider-crank",
                            "quick-return", "shaper", "garage-door", "tk-fourbar",
                            "jansen", "watt-sixbar", "whitworth", "toggle-press", "hoeken",
                            "boom-cylinder", "function-log10", "motion-3pose",
                            "path-timing", "triad-sixbar"])
    assert "[crank, dyad, point]" in next(line for line in out.stdout.splitlines()
                                          if line.startswith("fourbar "))


def test_help_teaches(tmp_path):
    out = run("build", "--help")
    assert out.returncode == 0
    assert "--set a2=40" in out.stdout and "--branch" in out.stdout


def test_the_process_ends_with_mains_status_and_all_its_output(bundled_books, tmp_path):
    """`python -m linkbook` ends the process with os._exit after main() (cli.run): the status
    is main's, 0, 1 or 2, and nothing printed is lost with stdout a pipe (block-buffered)."""
    book = tmp_path / "fb.xlsx"
    wb = openpyxl.load_workbook(bundled_books["fourbar"])
    wb["Sweep"]["H20"].value += "*1.001"
    wb.save(book)
    missing = tmp_path / "missing.xlsx"
    out = run("verify", str(book), str(book), str(missing))
    assert out.returncode == 2, out.stderr
    assert out.stdout.count("DISAGREES") == 2 and out.stdout.rstrip().endswith(
        "3 books: 0 agree, 2 disagree, 1 cannot be verified"), out.stdout[-300:]
    assert "missing.xlsx" in out.stderr
    out = run("verify", "--json", str(book))
    assert out.returncode == 1 and [r["status"] for r in json.loads(out.stdout)] == [1]


def test_the_process_ends_cleanly_without_stdout_and_under_a_profiler():
    env = dict(os.environ, PYTHONPATH=ENV_PATH)
    closed = subprocess.run(f'"{sys.executable}" -m linkbook list >&-', shell=True, env=env,
                            capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert closed.returncode == 0 and closed.stderr == "", closed.stderr
    # a profiler reports after the command returns: the exit is then Python's own
    profiled = subprocess.run([sys.executable, "-m", "cProfile", "-m", "linkbook", "list"],
                              env=env, capture_output=True, text=True, timeout=HANG_GUARD_S)
    assert profiled.returncode == 0 and "function calls" in profiled.stdout, profiled.stderr


def test_build_writes_a_workbook_with_defined_names(tmp_path):
    target = tmp_path / "fb.xlsx"
    out = run("build", "fourbar", "--set", "a2=40", "--branch", "crossed", "-o", str(target))
    assert out.returncode == 0, out.stderr
    wb = openpyxl.load_workbook(target)
    names = set(wb.defined_names.keys())
    assert {"a_1", "a_2", "a_3", "a_4", "b_3", "c_3", "Branch"} <= names
    def value_of(name):
        return wb["Mechanism"][wb.defined_names[name].attr_text.split("!")[1].replace("$", "")].value
    assert value_of("a_2") == 40 and value_of("Branch") == -1


BAD = [
    (("--set", "a2=-5"), "a2"),
    (("--set", "a2=abc"), "a2"),
    (("--set", "a9=3"), "a9"),
    (("--set", "a2=nan"), "a2"),
    (("--set", "a2=inf"), "a2"),
    (("--set", "a2=0"), "a2"),
    (("--set", "a2"), "--set"),
    (("--set", "branch=2"), "branch"),
    (("--step", "0"), "step"),
    (("--step", "-5"), "step"),
    (("--step", "x"), "step"),
    (("--step", "0.0001"), "step"),
]


@pytest.mark.parametrize("args,field", BAD, ids=[" ".join(a) for a, _ in BAD])
def test_bad_input_exits_2_with_one_line_and_no_file(tmp_path, args, field):
    target = tmp_path / "out.xlsx"
    out = run_in_process("build", "fourbar", *args, "-o", str(target))
    assert out.returncode == 2
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 1 and field in lines[0] and "Traceback" not in out.stderr, out.stderr
    assert list(tmp_path.iterdir()) == []


def test_unknown_key_suggests_the_nearest():
    out = run("build", "fourbar", "--set", "a22=5", "-o", "/tmp/never.xlsx")
    assert out.returncode == 2 and "did you mean a2" in out.stderr


def test_new_copies_a_bundled_template_and_never_overwrites(tmp_path):
    """After `pip install` the templates live inside the package: `new` copies one out, and the
    copy builds as the bundled one does."""
    out = run("new", "fourbar", "mine.toml", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    mine = tmp_path / "mine.toml"
    assert mine.read_text(encoding="utf-8") == (ROOT / "templates" / "fourbar.toml").read_text(
        encoding="utf-8")
    mine.write_text("# my own\n", encoding="utf-8")
    again = run("new", "slider-crank", "mine.toml", cwd=tmp_path)
    assert again.returncode == 2 and again.stderr.count("\n") == 1, again.stderr
    assert "mine.toml: exists already" in again.stderr
    assert mine.read_text(encoding="utf-8") == "# my own\n"
    typo = run("new", "fourbr", "other.toml", cwd=tmp_path)
    assert typo.returncode == 2 and "did you mean 'fourbar'?" in typo.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml"]


def test_check_validates_and_writes_nothing(tmp_path):
    text = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")
    (tmp_path / "good.toml").write_text(text, encoding="utf-8")
    (tmp_path / "bad.toml").write_text(text.replace('p_length = "a3"', 'p_lenght = "a3"'),
                                       encoding="utf-8")
    good = run("check", "good.toml", cwd=tmp_path)
    assert good.returncode == 0 and good.stdout.startswith("good.toml: ok"), good.stderr
    bad = run("check", "bad.toml", cwd=tmp_path)
    assert bad.returncode == 2 and bad.stderr == (
        "linkbook: error: bad.toml: mechanism.steps[1] (dyad B): unknown key 'p_lenght' (did "
        "you mean 'p_length'?)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml", "good.toml"]


def test_a_missing_toml_named_like_a_bundled_template_points_to_it(tmp_path):
    out = run("build", "fourbar.toml", cwd=tmp_path)
    assert out.returncode == 2
    assert "no such file 'fourbar.toml'; the bundled template is `fourbar`" in out.stderr
    assert "linkbook new fourbar fourbar.toml" in out.stderr
