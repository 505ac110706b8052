"""Every way a command can fail ends in one line, never a traceback, and leaves no file behind:
Ctrl-C and SIGTERM (exit 130 and 143), a file system that refuses the write (full, read-only,
a folder where a file belongs), and input that only looks like our fault (a build record that
is not an object or nests 1,000 deep, a TOML file nested too deeply or starting with a
byte-order mark, a 400-digit integer, a chart with nothing to plot, a sheet renamed in case only).
"""
from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import re
import signal
import subprocess
import sys
import zipfile
from pathlib import Path

import openpyxl
import pytest

from conftest import HANG_GUARD_S, ROOT, gone, said_pids, wait_until
from linkbook.apps import cli
from linkbook.base import sheets as layout

FOURBAR_TOML = (ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def book(coarse_fourbar) -> bytes:
    """A small four-bar book (30° steps), as file bytes."""
    return coarse_fourbar.read_bytes()


def _run(argv, capsys) -> tuple[int, list[str]]:
    code = cli.main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, (captured.out + captured.err).strip().splitlines()


def _one_error_line(code, lines, *must_hold) -> str:
    assert code == 2, lines
    assert len(lines) == 1 and lines[0].startswith("linkbook: error: "), lines
    assert "internal error" not in lines[0] and "Traceback" not in lines[0]
    for text in must_hold:
        assert text in lines[0], lines[0]
    return lines[0]


def _hidden_files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


# ---------------------------------------------------------------- signals
STALL = """
import importlib, sys, time
from linkbook.apps import cli
module = importlib.import_module("linkbook.{module}")
real = module.{function}

def stall(*args, **kwargs):      # mid-work: say so, then wait for the signal
    print("ready", flush=True)
    try:
        # Short sleeps, as a program at work runs Python between system calls: the kernel may
        # hand the signal to another thread (numpy's OpenBLAS server), whose handler then only
        # marks it for the main thread; one long sleep would not notice that for 120 s.
        for _ in range(1200):
            time.sleep(0.1)
    except BaseException:
        if not {swallow}:
            raise                    # else as a __del__ or a weakref callback would: dropped
    return real(*args, **kwargs)

module.{function} = stall
sys.argv[1:] = {argv!r}
cli.run()
"""


def _stopped_midway(tmp_path: Path, module: str, function: str, argv: list[str], signum,
                    swallow: bool = False):
    """Run the command in a process of its own, stalled inside `module.function` (the build:
    while the temporary file is being finished; verify: at the evaluation), and send `signum`
    once it says it got there; with `swallow`, the exception the signal raises there is
    dropped, as Python drops one raised inside a `__del__`. (exit status, stderr, the hidden
    files there were mid-way)."""
    code = STALL.format(module=module, function=function, argv=argv, swallow=swallow)
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "ready", proc.stderr.read()
        midway = _hidden_files(tmp_path)
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=HANG_GUARD_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    return proc.returncode, err, midway


@pytest.mark.parametrize("signum,status,name", [(signal.SIGINT, 130, "Ctrl-C (SIGINT)"),
                                                (signal.SIGTERM, 143, "SIGTERM")])
def test_a_signal_during_the_save_ends_in_one_line_and_leaves_no_temporary_file(
        tmp_path, signum, status, name):
    target = tmp_path / "fourbar.xlsx"
    target.write_bytes(b"the earlier book")
    code, err, midway = _stopped_midway(tmp_path, "book.package", "finish",
                                        ["build", "fourbar", "-o", "fourbar.xlsx"], signum)
    assert len(midway) == 1 and re.fullmatch(r"\.fourbar\.xlsx\..+\.tmp", midway[0]), midway
    assert code == status, err
    assert err.strip().splitlines() == [f"linkbook: stopped by {name}; no file is left "
                                        "half-written"], err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fourbar.xlsx"]
    assert target.read_bytes() == b"the earlier book"


@pytest.mark.parametrize("signum,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_signal_during_verify_ends_in_one_line(tmp_path, book, signum, status):
    (tmp_path / "fourbar.xlsx").write_bytes(book)
    code, err, _ = _stopped_midway(tmp_path, "engine.evaluator", "Engine",
                                   ["verify", "fourbar.xlsx"], signum)
    assert code == status and len(err.strip().splitlines()) == 1, err
    assert err.startswith("linkbook: stopped by"), err


@pytest.mark.parametrize("signum,status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
@pytest.mark.parametrize("module,function,argv", [
    ("book.package", "finish", ["build", "fourbar", "-o", "fourbar.xlsx"]),
    ("apps.info", "summary", ["info", "fourbar"])])
def test_a_signal_whose_exception_is_swallowed_still_stops_the_command(
        tmp_path, signum, status, module, function, argv):
    """The exception a signal raises can land where Python drops it (a `__del__`, a weakref
    callback, a library's `except BaseException`): the command must not go on to write its
    book or exit 0 as if nothing had come."""
    code, err, _ = _stopped_midway(tmp_path, module, function, argv, signum, swallow=True)
    assert code == status, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("linkbook: stopped by"), err
    assert list(tmp_path.iterdir()) == []


def test_sigterm_is_given_back_as_it_was_after_a_command(tmp_path):
    before = signal.getsignal(signal.SIGTERM)
    assert cli.main(["list"]) == 0
    assert signal.getsignal(signal.SIGTERM) is before


# ---------------------------------------------------------------- the file system says no
@pytest.mark.parametrize("number,reason", [(errno.ENOSPC, "the disk is full"),
                                           (errno.EROFS, "the file system is read-only"),
                                           (errno.EACCES, "permission denied")])
def test_a_refused_write_is_named_and_leaves_the_earlier_file(tmp_path, capsys, monkeypatch,
                                                              number, reason):
    """The save half done, then the file system refuses: one line naming the target (not the
    hidden temporary file) and the reason; the earlier book is untouched, nothing is left."""
    from linkbook.book import package
    target = tmp_path / "fourbar.xlsx"
    target.write_bytes(b"the earlier book")

    def refuse(src, dst, **kwargs):
        Path(dst).write_bytes(b"PK half a book")
        raise OSError(number, os.strerror(number), str(dst))
    monkeypatch.setattr(package, "finish", refuse)
    code, lines = _run(["build", "fourbar", "--step", "30", "-o", target], capsys)
    line = _one_error_line(code, lines, f"cannot write {target}: {reason}")
    assert ".tmp" not in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fourbar.xlsx"]
    assert target.read_bytes() == b"the earlier book"


@pytest.fixture
def small_disk(tmp_path):
    """A 40 kB tmpfs (a four-bar book is about 60 kB), where mounting one is allowed."""
    mount = tmp_path / "disk"
    mount.mkdir()
    made = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=40k", "tmpfs", str(mount)],
                          capture_output=True)
    if made.returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root): the faked refusals above stand in")
    yield mount
    subprocess.run(["umount", str(mount)], check=True)


def test_a_real_full_disk_and_a_real_read_only_mount(small_disk, capsys):
    code, lines = _run(["build", "fourbar", "--step", "30", "-o", small_disk / "x.xlsx"], capsys)
    _one_error_line(code, lines, f"cannot write {small_disk / 'x.xlsx'}: the disk is full")
    assert list(small_disk.iterdir()) == []
    subprocess.run(["mount", "-o", "remount,ro", str(small_disk)], check=True)
    code, lines = _run(["build", "fourbar", "--step", "30", "-o", small_disk / "x.xlsx"], capsys)
    _one_error_line(code, lines, "the file system is read-only")
    code, lines = _run(["build", "--all", "--outdir", small_disk / "books"], capsys)
    _one_error_line(code, lines, f"cannot make the folder {small_disk / 'books'}: the file "
                                 "system is read-only")


def test_a_folder_where_a_file_belongs_and_a_file_where_a_folder_belongs(tmp_path, capsys):
    (tmp_path / "book.xlsx").mkdir()
    (tmp_path / "plain").mkdir()
    (tmp_path / "notes.txt").write_text("a file")
    for out in ("book.xlsx", "plain"):
        code, lines = _run(["build", "fourbar", "-o", tmp_path / out], capsys)
        _one_error_line(code, lines, "-o: ", "is a folder; name a file in it")
    code, lines = _run(["build", "--all", "--outdir", tmp_path / "notes.txt"], capsys)
    _one_error_line(code, lines, "--outdir: ", "notes.txt' is a file, not a folder")
    code, lines = _run(["build", "fourbar", "-o", tmp_path / "notes.txt" / "x.xlsx"], capsys)
    _one_error_line(code, lines, "-o: ", "notes.txt' is a file, not a folder")
    code, lines = _run(["verify", tmp_path / "book.xlsx"], capsys)
    _one_error_line(code, lines, f"{tmp_path / 'book.xlsx'}: a folder, not a workbook")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["book.xlsx", "notes.txt", "plain"]


# ---------------------------------------------------------------- templates
def test_a_template_with_a_byte_order_mark_builds(tmp_path, capsys):
    """Windows editors (Notepad) start a UTF-8 file with U+FEFF; TOML without it is the same."""
    (tmp_path / "mine.toml").write_bytes("\ufeff".encode() + FOURBAR_TOML.encode())
    code, lines = _run(["build", tmp_path / "mine.toml", "-o", tmp_path / "mine.xlsx"], capsys)
    assert code == 0, lines
    assert openpyxl.load_workbook(tmp_path / "mine.xlsx")["Mechanism"]["A1"].value


TEMPLATES = [
    ("arrays nested 2,000 deep", "a = " + "[" * 2000 + "]" * 2000 + "\n" + FOURBAR_TOML,
     "mine.toml: nests tables or arrays too deeply to be read"),
    ("tables nested 600 deep", FOURBAR_TOML + "\nz = " + "{ x = " * 600 + "1" + " }" * 600,
     "mine.toml: nests tables or arrays too deeply to be read"),
    ("a 400-digit integer", FOURBAR_TOML.replace("value = 35.0", "value = " + "9" * 400),
     "a2.value: must be a finite number (got an integer of 400 digits)"),
    ("a chart with nothing to plot", FOURBAR_TOML.replace(
        'y = ["theta13_deg", "theta14_deg", "mu_deg"]', "y = []"),
     "mechanism.charts[0].y: must have at least 1 entry (got [])"),
    ("a chart plotting a list", FOURBAR_TOML.replace('y = ["yC"]', "y = [[1]]"),
     "mechanism.charts[1].y[0]: must be text (got [1])"),
]


@pytest.mark.parametrize("what,text,must_hold", TEMPLATES, ids=[t[0] for t in TEMPLATES])
def test_a_template_only_we_could_misread_is_the_users_error(tmp_path, capsys, what, text,
                                                             must_hold):
    (tmp_path / "mine.toml").write_text(text, encoding="utf-8")
    code, lines = _run(["build", tmp_path / "mine.toml", "-o", tmp_path / "mine.xlsx"], capsys)
    _one_error_line(code, lines, must_hold)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.toml"]


# ---------------------------------------------------------------- books
def _rewritten(raw: bytes, part: str, edit) -> bytes:
    """The book with one XML part edited as text."""
    src, out = zipfile.ZipFile(io.BytesIO(raw)), io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            body = src.read(info)
            if info.filename == part:
                new = edit(body.decode("utf-8"))
                assert new != body.decode("utf-8"), f"the edit did not apply to {part}"
                body = new.encode("utf-8")
            dst.writestr(info, body)
    return out.getvalue()


def _with_record(raw: bytes, text: str, path: Path) -> Path:
    """The book with its build record replaced by `text`."""
    wb = openpyxl.load_workbook(io.BytesIO(raw))
    ws = wb[layout.META]
    for row in range(2, ws.max_row + 1):
        ws.cell(row, 1).value = None
    ws["A2"] = text
    wb.save(path)
    return path


def _record(raw: bytes) -> dict:
    return layout.read_meta(openpyxl.load_workbook(io.BytesIO(raw)))


RECORDS = [
    ("a list", lambda m: [1, 2], "is damaged: it is not the JSON object"),
    ("a text", lambda m: "x", "is damaged: it is not the JSON object"),
    ("a number", lambda m: 5, "is damaged: it is not the JSON object"),
    ("nested 1,000 deep", lambda m: None, "is damaged: it is not the JSON object"),
    ("an object nested 1,000 deep", lambda m: "deep object", "is damaged"),
    ("the format as text", lambda m: {**m, "format": "1"}, "is damaged"),
    ("inputs a number", lambda m: {**m, "inputs": 5}, "does not match the workbook"),
    ("inputs missing", lambda m: {k: v for k, v in m.items() if k != "inputs"},
     "does not match the workbook"),
    ("an input a list", lambda m: {**m, "inputs": {**m["inputs"], "a2": [1]}},
     "does not match the workbook"),
    ("the sweep a number", lambda m: {**m, "sweep": 7}, "does not match the workbook"),
]


@pytest.mark.parametrize("what,change,must_hold", RECORDS, ids=[r[0] for r in RECORDS])
def test_a_damaged_build_record_is_named(tmp_path, capsys, book, what, change, must_hold):
    changed = change(_record(book))
    text = ("[" * 1000 + "]" * 1000 if changed is None else
            '{"format": 1, "x": ' + "[" * 1000 + "]" * 1000 + "}" if changed == "deep object"
            else json.dumps(changed))
    path = _with_record(book, text, tmp_path / "edited.xlsx")
    code, lines = _run(["verify", path], capsys)
    _one_error_line(code, lines, f"{path}: the build record (sheet linkbook) ", must_hold)


def test_a_400_digit_integer_in_an_input_cell_is_named(tmp_path, capsys, book):
    path = tmp_path / "huge.xlsx"
    path.write_bytes(_rewritten(book, "xl/worksheets/sheet1.xml", lambda xml: re.sub(
        r'(<c r="C8"[^>]*><v>)[^<]*(</v>)', lambda m: m[1] + "9" * 400 + m[2], xml)))
    code, lines = _run(["verify", path], capsys)
    # beyond a double's range: no spreadsheet reads it as that number
    _one_error_line(code, lines, f"{path}: xl/worksheets/sheet1.xml: cell Mechanism!C8 holds "
                                 f"'{'9' * 40}'… (400 characters), not a finite number")


@pytest.mark.parametrize("sheet", ["Sweep", "Mechanism"])
def test_a_sheet_renamed_only_in_case_is_named(tmp_path, capsys, book, sheet):
    path = tmp_path / "renamed.xlsx"
    path.write_bytes(_rewritten(book, "xl/workbook.xml", lambda xml: xml.replace(
        f'name="{sheet}"', f'name="{sheet.upper()}"')))
    code, lines = _run(["verify", path], capsys)
    line = _one_error_line(code, lines, f"the sheet '{sheet}' is missing (the book has "
                                        f"'{sheet.upper()}'")
    assert "KeyError" not in line


def test_the_sheet_of_the_inputs_deleted_is_named(tmp_path, capsys, book):
    wb = openpyxl.load_workbook(io.BytesIO(book))
    del wb["Mechanism"]
    wb.save(tmp_path / "no-inputs.xlsx")
    code, lines = _run(["verify", tmp_path / "no-inputs.xlsx"], capsys)
    line = _one_error_line(code, lines, "the sheet 'Mechanism' (the inputs) is missing")
    assert "KeyError" not in line


def test_openpyxls_three_line_message_is_one_line(tmp_path, capsys, book):
    """openpyxl's message on a cell it cannot read (a number written 0x10) runs over three
    lines ("... Please see the exception for more details."): it is joined into one, as the
    command, animate and preview see it."""
    from linkbook.base.safety import UnsafeFile, load_workbook_safely
    path = tmp_path / "hex.xlsx"
    path.write_bytes(_rewritten(book, "xl/worksheets/sheet1.xml", lambda xml: re.sub(
        r'(<c r="C8"[^>]*><v>)[^<]*(</v>)', lambda m: m[1] + "0x10" + m[2], xml)))
    with pytest.raises(UnsafeFile) as caught:
        load_workbook_safely(path)
    said = str(caught.value)
    assert "\n" not in said and "Please see the exception" in said, said
    code, lines = _run(["verify", path], capsys)
    _one_error_line(code, lines, str(path))


def test_a_signal_while_libreoffice_runs_ends_it_too(tmp_path):
    """LibreOffice runs in a session of its own (so that a time-out can end soffice.bin, the
    launcher's child): Ctrl-C reaches only us, and we end its whole process group."""
    from linkbook.engine import office
    pids = tmp_path / "pids"
    script = f"sleep {2 * HANG_GUARD_S} & echo $$ $! > {pids}; wait"   # outlives the guard
    interrupted = []

    def interrupt(signum, frame):
        """Ctrl-C once the shell and its child are both running (they said so), and only once."""
        if not interrupted and said_pids(pids, 2):
            interrupted.append(True)
            raise KeyboardInterrupt
    before = signal.signal(signal.SIGALRM, interrupt)
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.05, 0.05)
        with pytest.raises(KeyboardInterrupt):
            office._run(["sh", "-c", script], "sleeping")
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, before)
    try:
        for pid in said_pids(pids, 2):
            wait_until(lambda: gone(pid), f"the end of process {pid}")
    finally:
        for pid in said_pids(pids, 2):    # a failure of this test leaves nothing running
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
