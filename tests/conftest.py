"""Shared test helpers: building templates in memory, the published acceptance data, the
size of the property tests (hypothesis profiles) and the applications a test needs."""
from __future__ import annotations

import importlib.util
import os
import shutil
import subprocess
import sys
import time
import tomllib
from functools import lru_cache
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from linkbook.book import builder
from linkbook.engine import evaluator as engine
from linkbook.language import templates  # noqa: E402
from linkbook.check.verifier import check_book  # noqa: E402


PUBLISHED = ROOT / "tests" / "data" / "published.toml"
UNO_PYTHON = "/usr/bin/python3"         # the Python LibreOffice's bridge (python3-uno) is for


# ---------------------------------------------------------------- how many random examples
# One setting sizes every property test: `pytest --hypothesis-profile=fast` (the fast tier),
# none (the default, CI's) or `--hypothesis-profile=thorough` (a long run before a release).
# A test names its count at the default profile with examples(n); the profile scales it. Every
# profile is hypothesis' own CI profile (derandomized: the same examples here and in CI, no
# deadline, no example database), loaded here whether or not CI is set.
SCALE = {"fast": 0.05, "default": 1.0, "thorough": 5.0}
for _name, _scale in SCALE.items():
    settings.register_profile(_name, derandomize=True, deadline=None, database=None,
                              print_blob=True, suppress_health_check=[HealthCheck.too_slow],
                              max_examples=round(100 * _scale))
settings.load_profile("default")        # --hypothesis-profile, if given, is loaded after this


def pytest_report_header(config):
    return f"hypothesis profile: {settings.get_current_profile_name()} (tests/conftest.py)"


def examples(at_default: int, at_least: int = 1) -> int:
    """A property test's example count: `at_default` at the default profile, scaled by the
    profile chosen, never below `at_least` (what the test's own sanity checks need)."""
    return max(at_least, round(at_default * settings.default.max_examples / 100))


@lru_cache(maxsize=None)
def published() -> dict:
    """tests/data/published.toml: the numbers the sources printed (each entry names its source)."""
    return tomllib.loads(PUBLISHED.read_text(encoding="utf-8"))


def template(name: str, sets=(), step=None, branch=None) -> templates.Template:
    return templates.with_overrides(templates.load(name), list(sets), step, branch)


@lru_cache(maxsize=None)
def built(name: str, sets: tuple = (), step=None, branch=None):
    """(Built, values) of a template with overrides, evaluated by the vector engine."""
    return builder.make(template(name, sets, step, branch))


@pytest.fixture(scope="session")
def bundled_books(tmp_path_factory) -> dict[str, Path]:
    """name -> every bundled template's book as `linkbook build NAME` writes it, built once for
    the whole run. Read them; a test that changes a book or writes beside it copies it first."""
    folder = tmp_path_factory.mktemp("bundled")
    books = {}
    for path in templates.bundled():
        books[path.stem] = folder / f"{path.stem}.xlsx"
        builder.build_file(templates.load(path.stem), books[path.stem])
    return books


@pytest.fixture(scope="session")
def coarse_fourbar(tmp_path_factory) -> Path:
    """The four-bar at a 30° step (13 sweep rows) as `linkbook build fourbar --step 30` writes
    it, built once for the run: for tests whose point is a book's parts and formula shapes, not
    its row count. Read it; a test that changes it copies it first."""
    path = tmp_path_factory.mktemp("coarse") / "fourbar.xlsx"
    builder.build_file(template("fourbar", step=30.0), path)
    return path


@pytest.fixture(scope="session")
def recalculated_by_libreoffice(needs, bundled_books, tmp_path_factory) -> dict[str, Path]:
    """name -> the bundled book as LibreOffice recalculated and saved it (office.recalculate),
    every book in one run of soffice."""
    needs("libreoffice")
    from linkbook.engine import office
    out = tmp_path_factory.mktemp("recalculated")
    return dict(zip(bundled_books, office.recalculate_all(bundled_books.values(), out)))


@pytest.fixture(scope="module")
def _reports_made() -> dict:
    return {}


@pytest.fixture
def reports_once(_reports_made, monkeypatch):
    """verify's report of a book made once per test module (by path, engine and seed), for the
    tests of how reports are printed, which verify the same unchanged books again and again
    (`pytestmark = pytest.mark.usefixtures("reports_once")`). Not for a test that changes a
    book, or what reads it, between two verifications."""
    from linkbook.check import verifier
    make = verifier.report_of

    def made_once(path, engine: str = "vector", seed: int | None = None):
        key = (str(path), engine, seed)
        if key not in _reports_made:
            _reports_made[key] = make(path, engine, seed)
        return _reports_made[key]
    monkeypatch.setattr(verifier, "report_of", made_once)


def formula_cells(wb) -> set[tuple[str, str]]:
    return {(ws.title, c.coordinate) for ws in wb.worksheets for row in ws.iter_rows()
            for c in row if isinstance(c.value, str) and c.value.startswith("=")}


def checks_of(b, values):
    return check_book(b.workbook, b.record, values, engine.is_error, engine.error_code)


def passes_or_names_another_assembly(report) -> bool:
    """Exit status 0, or 2 for no reason but a triad's book reaching another assembly than the
    reference's (judge.note_other_assembly): the only named verdict a random triad may draw."""
    return report.status == 0 or (report.status == 2 and bool(report.other_assembly)
                                  and not report.unjudged and not report.not_judged
                                  and report.error is None)


def value_at(b, values, key: str, angle: float, sheet: str = "Sweep"):
    """The sweep value of column `key` on the row whose input angle is `angle`."""
    ws = b.workbook[sheet]
    first, last = b.meta["sweep"]["rows"]
    for r in range(first, last + 1):
        if abs(ws[f"A{r}"].value - angle) < 1e-9:
            return values[(sheet, f"{b.meta['sweep']['columns'][key]}{r}")]
    raise KeyError(angle)


def pytest_terminal_summary(terminalreporter):
    """Report how many random examples ran per family, and how many had unassembled rows."""
    try:
        from test_properties import TALLY
    except ImportError:
        return
    if not TALLY:
        return
    terminalreporter.section("property tests")
    for family in sorted({f for f, _ in TALLY}):
        terminalreporter.write_line(
            f"{family:24} {TALLY[(family, 'examples')]:5d} examples, "
            f"{TALLY[(family, 'with rows that cannot close')]:5d} with rows that cannot close"
            + (f", {TALLY[(family, 'tasks with no design')]} tasks with no design"
               if (family, "tasks with no design") in TALLY else "")
            + (f", {TALLY[(family, 'in another assembly after a restart')]} in another "
               "assembly after a restart"
               if (family, "in another assembly after a restart") in TALLY else ""))


# ---------------------------------------------------------------- applications a test needs
def _python_can_import(python: str, module: str) -> bool:
    return Path(python).is_file() and subprocess.run(
        [python, "-c", f"import {module}"], capture_output=True).returncode == 0


def _importable(module: str):
    return lambda: importlib.util.find_spec(module) is not None


# name -> (what it is, what installs it, whether this machine has it)
APPLICATIONS = {
    "libreoffice": ("LibreOffice (soffice)", ".ci/run's apt-get: libreoffice-calc-nogui",
                    lambda: bool(shutil.which("soffice") or shutil.which("libreoffice"))),
    "uno": ("LibreOffice's Python bridge", ".ci/run's apt-get: python3-uno",
            lambda: _python_can_import(UNO_PYTHON, "uno")),
    "pdftoppm": ("pdftoppm", ".ci/run's apt-get: poppler-utils",
                 lambda: bool(shutil.which("pdftoppm"))),
    "gnumeric": ("Gnumeric (ssconvert)", ".ci/run's apt-get: gnumeric",
                 lambda: bool(shutil.which("ssconvert"))),
    "strace": ("strace", ".ci/run's apt-get: strace", lambda: bool(shutil.which("strace"))),
    "ironcalc": ("IronCalc (ironcalc)", "pip install '.[test]'", _importable("ironcalc")),
    "pylinkage": ("pylinkage", "pip install '.[test]'", _importable("pylinkage")),
    "pandas": ("pandas", "pip install '.[test]'", _importable("pandas")),
    "calamine": ("python-calamine", "pip install '.[test]'", _importable("python_calamine")),
    "ffmpeg": ("imageio-ffmpeg", "pip install '.[test]'", _importable("imageio_ffmpeg")),
    "lxml": ("lxml", "pip install '.[test]' (openxml-audit's)", _importable("lxml")),
}


@lru_cache(maxsize=None)
def _have(name: str) -> bool:
    return APPLICATIONS[name][2]()


def _need(*names: str) -> None:
    """Skip the test without any of these applications, saying which; under CI (the variable
    CI set, as .ci/run sets it) fail instead: a check that did not run never passes there."""
    missing = [n for n in names if not _have(n)]
    if not missing:
        return
    reason = "needs " + ", ".join(APPLICATIONS[n][0] for n in missing)
    if os.environ.get("CI"):
        pytest.fail(f"CI {reason} (" + "; ".join(APPLICATIONS[n][1] for n in missing) + ")",
                    pytrace=False)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def needs():
    """needs("libreoffice", "pdftoppm"): see _need(); usable in fixtures of any scope."""
    return _need


# ---------------------------------------------------------------- waiting on what a process does
HANG_GUARD_S = 300      # only a hung process takes this long, however loaded the machine


def wait_until(happened, what: str, guard_s: float = HANG_GUARD_S) -> None:
    """Poll `happened()` until it is true: a test waits on an event (a file a child writes, a
    process gone), never on a delay a loaded machine overruns. Fails after `guard_s`, which
    only a hang reaches."""
    give_up = time.monotonic() + guard_s
    while not happened():
        if time.monotonic() > give_up:
            pytest.fail(f"{what} did not happen within {guard_s} s", pytrace=False)
        time.sleep(0.02)


def gone(pid: int) -> bool:
    """The process has ended: no such process, or a zombie (an orphan is reaped by whoever
    adopts it, when it gets to it)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except FileNotFoundError:
        return True
    return state in ("Z", "X")


def said_pids(path: Path, count: int) -> list[int] | None:
    """The `count` process ids a shell wrote to `path` with one echo, once the line is whole."""
    text = path.read_text() if path.exists() else ""
    return [int(w) for w in text.split()] if text.endswith("\n") and \
        len(text.split()) == count else None
