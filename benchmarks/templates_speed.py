"""Build and verify time of every bundled template at its default step, whole process (Python
start-up and imports included), medians of --runs runs; and the *work* of each: the same build
and verify, each in a fresh process of its own, timed after the modules they use are imported
(start-up and imports left out, first-call costs kept). With --against DIR (another checkout of
linkbook, e.g. a git worktree of an older commit) the same commands run from that tree too,
interleaved in the same run, and the table gives both medians and their ratio.

    python benchmarks/templates_speed.py [--runs 5] [--against /tmp/old-linkbook]
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bytecode import compile_tree

ROOT = Path(__file__).resolve().parents[1]


def timed(tree: Path, args: list[str]) -> float:
    env = {**os.environ, "PYTHONPATH": str(tree / "src"), "TQDM_DISABLE": "1"}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "linkbook", *args], env=env,
                          capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"{tree}: linkbook {' '.join(args)} failed:\n{proc.stderr}")
    return seconds


WORK = """
import contextlib, importlib, io, sys, time
from pathlib import Path
import openpyxl, numpy

def first(*names):      # the module where this checkout has it (wings, or the older flat layout)
    for name in names:
        try:
            return importlib.import_module(name)
        except ImportError:
            pass
    raise ImportError(names[0])

cli = first("linkbook.apps.cli", "linkbook.cli")
for wing, flat in (("book.builder", "builder"), ("book.charts", "charts"), ("book.package", "package"),
                   ("book.workbook", "workbook"), ("check.verifier", "verifier"),
                   ("engine.evaluator", "engine"), ("engine.office", "office")):
    first("linkbook." + wing, "linkbook." + flat)
args = ["build", sys.argv[2], "-o", sys.argv[3]] if sys.argv[1] == "build" else sys.argv[1:]
with contextlib.redirect_stdout(io.StringIO()):
    start = time.perf_counter()
    assert cli.main(args) == 0
    print(time.perf_counter() - start, file=sys.stderr)
"""


def work(tree: Path, job: str, *args: str) -> float:
    """Seconds of work of one `linkbook build` or `verify` in a fresh process, timed after the
    imports.  Each job has its own process: a verify after a build in the same process would
    reuse the formulas the build compiled."""
    env = {**os.environ, "PYTHONPATH": str(tree / "src"), "TQDM_DISABLE": "1"}
    proc = subprocess.run([sys.executable, "-c", WORK, job, *args], env=env,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{tree}: {job} work failed:\n{proc.stderr}")
    return float(proc.stderr.split()[-1])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--against", type=Path, help="another linkbook checkout to compare with")
    opts = ap.parse_args()
    trees = {"now": ROOT} | ({"other": opts.against.resolve()} if opts.against else {})
    for tree in trees.values():
        compile_tree(tree / "src")
    names = sorted(p.stem for p in (ROOT / "templates").glob("*.toml"))
    results: dict[tuple[str, str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            for _ in range(opts.runs):
                for label, tree in trees.items():       # interleaved: same machine state
                    if not (tree / "templates" / f"{name}.toml").is_file():
                        continue
                    book = str(Path(tmp) / f"{label}-{name}.xlsx")
                    results.setdefault((name, label, "build"), []).append(
                        timed(tree, ["build", name, "-o", book]))
                    results.setdefault((name, label, "verify"), []).append(
                        timed(tree, ["verify", book]))
                    results.setdefault((name, label, "build work"), []).append(
                        work(tree, "build", name, book))
                    results.setdefault((name, label, "verify work"), []).append(
                        work(tree, "verify", book))
            print(f"{name}: done", file=sys.stderr, flush=True)
    jobs = ("build", "verify", "build work", "verify work")
    cols = [(label, job) for label in trees for job in jobs]
    print(f"{'template':22}" + "".join(f"{label + ' ' + job:>18}" for label, job in cols)
          + ("".join(f"{'now/other ' + job:>22}" for job in jobs) if opts.against else ""))
    for name in names:
        med = {k: statistics.median(v) for k, v in results.items() if k[0] == name}
        row = f"{name:22}" + "".join(
            f"{med[(name, label, job)]:17.2f}s" if (name, label, job) in med else f"{'-':>18}"
            for label, job in cols)
        if opts.against:
            for job in jobs:
                a, b = med.get((name, "now", job)), med.get((name, "other", job))
                row += f"{a / b:21.2f}x" if a and b else f"{'-':>22}"
        print(row)
    print(f"\nmedians of {opts.runs} runs; build and verify: whole process (start-up and imports"
          " included, modules compiled to bytecode as pip installs them); work: the same, each"
          " in a fresh process, after the imports"
          + (f"; other = {opts.against}" if opts.against else ""))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
