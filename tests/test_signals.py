"""Ctrl-C and SIGTERM sent to every command at a spread of moments, from the first line of
linkbook's entry point to the end: each delivery ends the command with 130 or 143 and one line
(or, sent after the command had already ended, changes nothing), never with a traceback, an
"Exception ignored" or exit 0, and a command stopped by a signal leaves no file of its output.

The moments are fixed delays after the child says it is about to call the entry point (Python's
own start-up before that is Python's, not linkbook's); what each delivery hit depends on the
machine's load, so each is judged only on what happened to it.
"""
from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import HANG_GUARD_S, ROOT

# The console script pip writes, with one line said before the entry point is called.
ENTRY = """import sys
from linkbook.apps.cli import run
sys.argv[1:] = {argv!r}
print("go", flush=True)
sys.exit(run())
"""
# each command with the files it writes (none: it writes nothing)
COMMANDS = {
    "build": (["build", "fourbar", "--step", "30", "-o", "out.xlsx"], ["out.xlsx"]),
    "verify": (["verify", "book.xlsx"], []),
    "info": (["info", "book.xlsx"], []),
    "export": (["export", "book.xlsx", "-o", "tables"], ["tables"]),
    "animate": (["animate", "book.xlsx", "-o", "out.gif", "--size", "100"], ["out.gif"]),
    "check": (["check", "fourbar"], []),
    "list": (["list"], []),
}
DELAYS = (0.0, 0.03, 0.1, 0.2, 0.35, 0.6)        # seconds after "go"
STOPS = {signal.SIGINT: 130, signal.SIGTERM: 143}
NAMES = {signal.SIGINT: "Ctrl-C (SIGINT)", signal.SIGTERM: "SIGTERM"}


@pytest.fixture(scope="module")
def book(coarse_fourbar) -> bytes:
    return coarse_fourbar.read_bytes()


def _deliver(folder: Path, argv: list[str], signum: int, delay: float):
    """Run the command, send `signum` `delay` s after its "go"; (exit status, stderr, whether
    the command had already ended when the signal was due: then nothing was sent).

    The child is first stopped (SIGSTOP), so that whether it had ended is known for certain
    before the signal goes: a stopped child cannot end in between, and the signal waits for it
    to continue as it would have landed at that moment."""
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.Popen([sys.executable, "-c", ENTRY.format(argv=argv)], cwd=folder,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline() == "go\n"
        if delay:
            try:
                proc.wait(timeout=delay)
            except subprocess.TimeoutExpired:
                pass
        ended_first = proc.returncode is not None or _ended_before_stopping(proc.pid)
        while not ended_first and not _handlers_in_place(proc.pid):
            # between "go" and the entry point's first line: Python's, not linkbook's, moment
            os.kill(proc.pid, signal.SIGCONT)
            ended_first = _ended_before_stopping(proc.pid)
        if not ended_first:
            os.kill(proc.pid, signum)
            os.kill(proc.pid, signal.SIGCONT)
        _, err = proc.communicate(timeout=HANG_GUARD_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    return proc.returncode, err, ended_first


def _ended_before_stopping(pid: int) -> bool:
    """Stop the child; True if it had ended before (it is left to be reaped as it was)."""
    os.kill(pid, signal.SIGSTOP)
    state = os.waitid(os.P_PID, pid, os.WSTOPPED | os.WEXITED | os.WNOWAIT)
    return state.si_code != os.CLD_STOPPED


def _handlers_in_place(pid: int) -> bool:
    """Whether the process catches SIGTERM (Python's own start-up leaves it to the system)."""
    status = Path(f"/proc/{pid}/status").read_text()
    caught = int(re.search(r"^SigCgt:\s*([0-9a-f]+)$", status, re.M).group(1), 16)
    return bool(caught >> (signal.SIGTERM - 1) & 1)


def test_the_entry_module_imports_only_what_it_needs_before_it_takes_the_signals():
    """What `linkbook.apps.cli` imports runs before its run() has the signals in hand (a Ctrl-C
    there is Python's traceback), so it must stay light: no wing but base, no numpy, no
    openpyxl, not even argparse."""
    code = "import sys, linkbook.apps.cli; print(' '.join(sorted(sys.modules)))"
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    loaded = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                            text=True, check=True).stdout.split()
    ours = {m for m in loaded if m.startswith("linkbook.")}
    assert ours <= {"linkbook.base", "linkbook.base.errors", "linkbook.base.stopping",
                    "linkbook.apps", "linkbook.apps.cli"}, ours
    assert not {"numpy", "openpyxl", "formulas", "argparse"} & set(loaded)


@pytest.mark.slow
@pytest.mark.parametrize("command", COMMANDS)
def test_a_signal_at_any_moment_ends_the_command_in_one_line(tmp_path, book, command):
    argv, outputs = COMMANDS[command]
    for i, delay in enumerate(DELAYS):
        for signum, status in STOPS.items():
            folder = tmp_path / f"{i}-{signum}"
            folder.mkdir()
            (folder / "book.xlsx").write_bytes(book)
            code, err, ended_first = _deliver(folder, argv, signum, delay)
            what = f"{command}, signal {signum} {delay} s in: exit {code}, stderr {err!r}"
            assert "Traceback" not in err and "Exception ignored" not in err, what
            left = sorted(p.name for p in folder.iterdir() if p.name != "book.xlsx")
            if ended_first:
                assert code in (0, 1), what
                continue
            assert code == status, what
            assert err.strip().splitlines() == [f"linkbook: stopped by {NAMES[signum]}; no "
                                                "file is left half-written"], what
            assert not [name for name in left if name in outputs and not _empty(folder / name)
                        or name.startswith(".")], what


def _empty(path: Path) -> bool:
    return path.is_dir() and not any(path.iterdir())
