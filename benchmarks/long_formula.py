"""What one very long formula costs: whole-process time and peak memory.

A bundled four-bar whose Mechanism!I9 (``I17-a_1``) is rewritten as ``(I17-a_1)+0+0…`` of 10 k,
100 k and 1 M characters — tens of KB on disk once zipped. For each length, two child
processes, each measured alone (os.wait4 gives that child's own peak resident memory):

- ``linkbook verify`` of the book: Excel holds at most 8,192 characters in a formula, so verify
  must refuse it (exit 2) at once, in bounded memory;
- the formula grammar (linkbook.engine.grammar.parse) alone on the formula, which any caller of the
  engine may hand it: its memory must grow linearly with the length.

A child that passes its limit (--memory, --seconds) is stopped and shown as over it.

    python benchmarks/long_formula.py [--lengths 10000,100000,1000000]
"""
from __future__ import annotations

import argparse
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CELL = '<c r="I9" s="8"><f>I17-a_1</f>'
GRAMMAR_ONLY = """
import sys
from linkbook.engine import adapter, grammar
formula = open(sys.argv[1], encoding="utf-8").read()
parsed = grammar.parse(formula, adapter.plain_functions())
print(f"parsed: {len(parsed.nodes):,} nodes" if parsed else "outside the grammar")
"""


def long_formula(length: int) -> str:
    """``(I17-a_1)+0+0…``, `length` characters or one fewer: the cell's value is unchanged."""
    head = "(I17-a_1)"
    return head + "+0" * ((length - len(head)) // 2)


SOURCE = [ROOT / "src"]      # the linkbook measured (--src: another checkout's)


def damaged_book(folder: Path, formula: str) -> Path:
    env = dict(os.environ, PYTHONPATH=str(ROOT / "src"))      # built by this checkout
    clean = folder / "fourbar.xlsx"
    if not clean.exists():
        subprocess.run([sys.executable, "-m", "linkbook", "build", "fourbar", "-o", str(clean)],
                       env=env, check=True, capture_output=True)
    path = folder / f"fourbar-{len(formula)}.xlsx"
    with zipfile.ZipFile(clean) as src, zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as dst:
        for info in src.infolist():
            data = src.read(info)
            if info.filename == "xl/worksheets/sheet1.xml":
                assert CELL.encode() in data
                data = data.replace(CELL.encode(), CELL.replace("I17-a_1", formula).encode())
            dst.writestr(info, data, compress_type=zipfile.ZIP_DEFLATED)
    return path


def measured(argv: list[str], memory: int, seconds: float) -> tuple[float, float, str]:
    """(seconds, peak MiB, last line or what stopped it) of one child process, reaped with
    os.wait4 for its own resource usage."""
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    env = dict(os.environ, PYTHONPATH=str(SOURCE[0]))
    with tempfile.TemporaryFile("w+") as out:
        start = time.perf_counter()
        child = subprocess.Popen(argv, env=env, stdout=out, stderr=subprocess.STDOUT,
                                 preexec_fn=limit)
        timer = threading.Timer(seconds, child.kill)
        timer.start()
        _, status, usage = os.wait4(child.pid, 0)
        took = time.perf_counter() - start
        timer.cancel()
        child.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read()
    lines = [line for line in text.strip().splitlines() if line.strip()]
    last = lines[-1] if lines else f"exit {child.returncode}"
    if took >= seconds:
        last = f"stopped at the {seconds:g} s limit"
    elif "MemoryError" in text:
        last = f"stopped at the {memory / 2 ** 30:g} GiB limit (MemoryError)"
    return took, usage.ru_maxrss / 1024, last


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--lengths", default="10000,100000,1000000")
    parser.add_argument("--memory", type=float, default=3.0, help="GiB a child may map")
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--src", type=Path, default=SOURCE[0], help="the src folder to measure")
    args = parser.parse_args()
    SOURCE[0] = args.src.resolve()
    memory = int(args.memory * 2 ** 30)
    folder = Path(tempfile.mkdtemp(prefix="long-formula-"))
    try:
        print(f"{'characters':>10}  {'what':<16} {'seconds':>8} {'peak MiB':>9}  answer")
        for length in map(int, args.lengths.split(",")):
            formula = long_formula(length)
            book = damaged_book(folder, formula)
            text = folder / f"formula-{length}.txt"
            text.write_text("=" + formula, encoding="utf-8")
            for what, argv in (
                    ("verify", [sys.executable, "-m", "linkbook", "verify", str(book)]),
                    ("grammar.parse", [sys.executable, "-c", GRAMMAR_ONLY, str(text)])):
                took, peak, last = measured(argv, memory, args.seconds)
                last = last.replace(f"{book}: ", "").replace("linkbook: error: ", "")
                print(f"{len(formula):>10,}  {what:<16} {took:8.2f} {peak:9.0f}  {last}",
                      flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
