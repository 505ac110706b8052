"""Speed of verification, measured in one run on this machine (a script, not a test).

For each case (four-bar at 5°, 1°, 0.1°; pump grid 20° × 6 and 1° × 51; with --templates, also
every bundled template at its default step) it measures, each in a fresh Python process (wall time
and peak memory of that process):
  build      linkbook build (layout, one evaluation for chart scales, save)
  vector     linkbook verify --engine vector (load, evaluate every formula cell, reference, compare)
  excelmodel formulas' ExcelModel on the same file (skipped where a per-cell cost calibrated in
             this run predicts more than 2 minutes, or stopped after 2 minutes)
  office     LibreOffice headless full recalculation (if soffice is installed)
  reference  the numpy reference alone, for the same angles and adjustments
and prints a table with ratios against ExcelModel and against the reference.

Then, side by side in the same run, the whole-process wall time (medians of --runs runs) of
  build      `python -m linkbook build NAME ...` (the case's book, written again)
  verify     `python -m linkbook verify BOOK`
  office     LibreOffice's headless recalculation (the soffice process linkbook.engine.office runs)
  ironcalc   `python -c "import ironcalc; load_from_xlsx(BOOK).evaluate()"` (if the optional
             `ironcalc` package is installed: pip install ironcalc)
  excelmodel the ExcelModel job's process (one run; where it ran)
with the ratios the issue's targets are stated in.

--issue measures only what issue 42's targets are stated in, whole processes side by side in one
run (medians of --runs runs, the tools interleaved run by run): the bundled four-bar, the 0.1°
four-bar and slider-crank (with their Forces sheets) and the 1° × 51 pump grid; for each, verify,
IronCalc and LibreOffice (wall and the process's peak memory: the operating system's own
accounting of the finished process) and the import floor (`python -c "import numpy, openpyxl,
formulas"`). It prints the issue's table. With --against DIR (another checkout of linkbook, e.g.
`git worktree add /tmp/old HEAD~3`) that tree's verify runs interleaved too, as "before".

    python benchmarks/verify_speed.py [--json results.json] [--only fourbar-1] [--templates]
                                      [--runs 3]
    python benchmarks/verify_speed.py --issue [--runs 5] [--against /tmp/old-linkbook]
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from bytecode import compile_tree

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
EXCELMODEL_LIMIT_S = 120.0

PUMP_51 = ",".join(str(v) for v in range(0, 251, 5))     # 51 adjustments s1 = 0 … 250 mm
CASES = {
    "fourbar-5": ("fourbar", ["--step", "5"]),
    "fourbar-1": ("fourbar", ["--step", "1"]),
    "fourbar-0.1": ("fourbar", ["--step", "0.1"]),
    "slider-crank-0.1": ("slider-crank", ["--step", "0.1"]),
    "pump-20x6": ("pump", []),
    "pump-1x51": ("pump", ["--step", "1", "--set", f"s1={PUMP_51}"]),
}
# issue 42's books: its targets are stated on these (the bundled four-bar is at its 5°)
ISSUE_CASES = ("fourbar-5", "fourbar-0.1", "slider-crank-0.1", "pump-1x51")
FLOOR = [sys.executable, "-c", "import numpy, openpyxl, formulas"]

# Each job runs in its own interpreter and prints a JSON line: {"seconds": …, "peak_mb": …, …}.
JOBS = {
    "build": """
from linkbook.apps.cli import main
assert main(["build", NAME, *ARGS, "-o", BOOK]) == 0
""",
    "vector": """
from linkbook.check.verifier import verify
report = verify(Path(BOOK), "vector")
EXTRA["ok"] = report.ok
EXTRA["cells"] = report.cells
EXTRA["max_abs"] = report.max_abs
""",
    "excelmodel": """
from linkbook.engine.evaluator import evaluate_formulas_model
EXTRA["cells"] = len(evaluate_formulas_model(Path(BOOK)))
""",
    "office": """
from linkbook.engine.office import recalculate
with tempfile.TemporaryDirectory() as d:
    recalculate(Path(BOOK), Path(d))
""",
    "reference": """
from linkbook.base.safety import load_workbook_safely
from linkbook.check.verifier import Reference, inputs_of
from linkbook.base.sheets import read_meta
wb = load_workbook_safely(Path(BOOK))
meta = read_meta(wb)
params = inputs_of(wb, meta)
t0 = time.perf_counter()
reference = Reference(meta)
ws = wb[meta["sweep"]["sheet"]]
r0, r1 = meta["sweep"]["rows"]
angles = [ws[f"A{r}"].value for r in range(r0, r1 + 1)]
reference.solve(params, angles)
if "grid" in meta:
    g = wb["Grid"]
    for block in (meta["grid"], meta["stroke"]):
        bws = wb[block["sheet"]]
        a = [bws[f"A{r}"].value for r in range(block["rows"][0], block["rows"][1] + 1)]
        for c in meta["grid"]["columns"]:
            s1 = g[f"{c}{meta['grid']['param_row']}"].value
            reference.solve({**params, meta["grid"]["param"]: s1}, a)
EXTRA["solve_seconds"] = time.perf_counter() - t0
""",
}

# Libraries (and `formulas`' lazily imported function modules, about a second) are loaded before
# the clock starts, the same for every job: "seconds" is the work itself; "wall" adds start-up.
PRELUDE = """
import json, resource, sys, tempfile, time
from pathlib import Path
sys.path.insert(0, {src!r})
import formulas, numpy, openpyxl
from formulas.functions import get_functions
get_functions()
import linkbook.apps.cli, linkbook.engine.evaluator, linkbook.check.verifier
NAME, ARGS, BOOK = {name!r}, {args!r}, {book!r}
EXTRA = {{}}
t0 = time.perf_counter()
"""
POSTLUDE = """
seconds = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps({"seconds": seconds, "peak_mb": peak, **EXTRA}))
"""


def run_job(job: str, name: str, args: list[str], book: Path, timeout: float = 1800) -> dict:
    code = PRELUDE.format(src=str(SRC), name=name, args=args, book=str(book)) + JOBS[job] + POSTLUDE
    start = time.perf_counter()
    try:
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                              timeout=timeout, env={**os.environ, "TQDM_DISABLE": "1"})
    except subprocess.TimeoutExpired:
        return {"skipped": f"over {timeout:.0f} s"}
    wall = time.perf_counter() - start
    if proc.returncode != 0:
        return {"error": proc.stderr.strip().splitlines()[-1] if proc.stderr else "failed",
                "wall": wall}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out["wall"] = wall      # whole process, interpreter start-up and imports included
    return out


IRONCALC = """
import sys, ironcalc
model = ironcalc.load_from_xlsx(sys.argv[1], "en", "UTC")
model.evaluate()
"""


def wall(command: list[str]) -> float:
    start = time.perf_counter()
    proc = subprocess.run(command, capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(SRC), "TQDM_DISABLE": "1"})
    seconds = time.perf_counter() - start
    if proc.returncode not in (0, 1):          # verify exits 1 on a failed check: still timed
        raise SystemExit(f"{' '.join(command)} failed:\n{proc.stderr}")
    return seconds


def whole_process(name: str, args: list[str], book: Path, runs: int, office: bool,
                  ironcalc: bool) -> dict[str, float]:
    """Medians of `runs` whole-process wall times, the tools interleaved run by run."""
    times: dict[str, list[float]] = {}
    rebuilt = book.with_name(f"{book.stem}-rebuilt.xlsx")
    for _ in range(runs):
        times.setdefault("build", []).append(
            wall([sys.executable, "-m", "linkbook", "build", name, *args, "-o", str(rebuilt)]))
        times.setdefault("verify", []).append(
            wall([sys.executable, "-m", "linkbook", "verify", str(book)]))
        if ironcalc:
            times.setdefault("ironcalc", []).append(
                wall([sys.executable, "-c", IRONCALC, str(book)]))
        if office:
            times.setdefault("office", []).append(
                run_job("office", name, args, book)["seconds"])   # the soffice process alone
    return {tool: statistics.median(v) for tool, v in times.items()}


def measured(command: list[str], src: Path = SRC) -> tuple[float, float, float]:
    """(wall seconds, peak resident MiB, CPU seconds) of one whole process: the operating
    system's own accounting of the finished child (wait4), not of this script. A command that
    prints a JSON line {"peak_mb": …, "cpu": …} last (OFFICE: of the application it waited for)
    has that peak if larger, and that CPU time added.
    Linux counts a child's peak from its fork, so this script stays small (it imports no
    numpy or openpyxl): FLOOR_NOTE says how small."""
    env = {**os.environ, "PYTHONPATH": str(src), "TQDM_DISABLE": "1"}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        start = time.perf_counter()
        proc = subprocess.Popen(command, env=env, stdout=out, stderr=err)
        _, status, usage = os.wait4(proc.pid, 0)
        seconds = time.perf_counter() - start
        code = proc.returncode = os.waitstatus_to_exitcode(status)
        if code not in (0, 1):          # verify exits 1 on a failed check: still timed
            err.seek(0)
            raise SystemExit(f"{' '.join(command)} failed (exit {code}):\n"
                             f"{err.read().decode()}")
        out.seek(0)
        last = (out.read().decode().strip().splitlines() or [""])[-1]
    peak, cpu = usage.ru_maxrss / 1024, usage.ru_utime + usage.ru_stime
    if last.startswith('{"peak_mb"'):
        child = json.loads(last)
        peak, cpu = max(peak, child["peak_mb"]), cpu + child["cpu"]
    return seconds, peak, cpu


# LibreOffice's recalculation of a book, from a process that imports only linkbook's office
# module: the peak is the largest process it waited for (soffice)
OFFICE = """
import json, resource, sys, tempfile
from pathlib import Path
from linkbook.engine.office import recalculate
with tempfile.TemporaryDirectory() as d:
    recalculate(Path(sys.argv[1]), Path(d))
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"peak_mb": usage.ru_maxrss / 1024, "cpu": usage.ru_utime + usage.ru_stime}))
"""
COUNT_CELLS = """
import sys, openpyxl
wb = openpyxl.load_workbook(sys.argv[1])
print(sum(1 for ws in wb.worksheets for row in ws.iter_rows() for c in row
          if isinstance(c.value, str) and c.value.startswith("=")))
"""


def issue_table(cases: dict, runs: int, against: Path | None, office: bool,
                ironcalc: bool) -> dict:
    """Issue 42's measurements: each case's whole processes, medians of `runs` runs, the tools
    interleaved run by run (ratios hold when the machine's speed drifts)."""
    results = {}
    with tempfile.TemporaryDirectory() as tmp:
        for case in ISSUE_CASES:
            name, args = cases[case]
            book = Path(tmp) / f"{case}.xlsx"
            if "error" in run_job("build", name, args, book):
                raise SystemExit(f"{case}: the book could not be built")
            runs_of: dict[str, list[tuple[float, float, float]]] = {}
            tools = {"verify": lambda: measured([sys.executable, "-m", "linkbook", "verify",
                                                 str(book)]),
                     "floor": lambda: measured(FLOOR)}
            if against is not None:
                tools["before"] = lambda: measured(
                    [sys.executable, "-m", "linkbook", "verify", str(book)], against / "src")
            if ironcalc:
                tools["ironcalc"] = lambda: measured([sys.executable, "-c", IRONCALC,
                                                      str(book)])
            if office:
                tools["office"] = lambda: measured([sys.executable, "-c", OFFICE, str(book)])
            for _ in range(runs):
                for tool, run in tools.items():
                    runs_of.setdefault(tool, []).append(run())
            cells = subprocess.run([sys.executable, "-c", COUNT_CELLS, str(book)],
                                   capture_output=True, text=True, check=True).stdout
            results[case] = {"cells": int(cells), **{
                tool: {"wall": statistics.median(w for w, _, _ in v),
                       "peak_mb": statistics.median(m for _, m, _ in v),
                       "cpu": statistics.median(c for _, _, c in v), "runs": v}
                for tool, v in runs_of.items()}}
            print(f"{case}: done", file=sys.stderr, flush=True)
    return results


def print_issue(results: dict, runs: int) -> None:
    """The issue's table: verify against IronCalc and LibreOffice, wall and peak memory."""
    def ratio(r: dict, a: str, b: str, key: str) -> str:
        """The median of the runs' ratios, run by run (the tools ran in turn): a ratio holds
        while the machine's speed drifts, where a ratio of medians need not."""
        if a not in r or b not in r:
            return "-"
        k = ("wall", "peak_mb", "cpu").index(key)
        pairs = zip(r[a]["runs"], r[b]["runs"])
        return f"{statistics.median(x[k] / y[k] for x, y in pairs):.2f}×"

    def both(r: dict, tool: str) -> str:
        return f"{r[tool]['wall']:.2f} s, {r[tool]['peak_mb']:.0f} MiB" if tool in r else "-"
    print(f"\nWhole process, medians of {runs} interleaved runs (wall; peak resident memory); "
          "ratios: medians of the runs' ratios")
    before = any("before" in r for r in results.values())
    print("| book (formula cells) | verify | IronCalc 0.9.1 | LibreOffice | verify / IronCalc "
          "(wall) | verify / IronCalc (CPU) | verify / IronCalc (peak) | verify / LibreOffice "
          "(wall) | verify / import floor (wall) |"
          + (" before / after (wall; CPU) |" if before else ""))
    print("|---|---|---|---|---|---|---|---|---|" + ("---|" if before else ""))
    for case, r in results.items():
        row = (f"| {case} ({r['cells']:,}) | {both(r, 'verify')} | {both(r, 'ironcalc')} | "
               f"{both(r, 'office')} | {ratio(r, 'verify', 'ironcalc', 'wall')} | "
               f"{ratio(r, 'verify', 'ironcalc', 'cpu')} | "
               f"{ratio(r, 'verify', 'ironcalc', 'peak_mb')} | "
               f"{ratio(r, 'verify', 'office', 'wall')} | {ratio(r, 'verify', 'floor', 'wall')} |")
        if "before" in r:
            row += (f" {ratio(r, 'before', 'verify', 'wall')}; CPU "
                    f"{ratio(r, 'before', 'verify', 'cpu')} ({both(r, 'before')}) |")
        print(row)
    print("import floor: `python -c \"import numpy, openpyxl, formulas\"`; LibreOffice: its "
          "headless recalculation (soffice, started from a small Python process); peaks are "
          "counted from at least this script's own "
          f"{resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024:.0f} MiB")


def formula_cells(book: Path) -> int:
    sys.path.insert(0, str(SRC))
    import openpyxl
    wb = openpyxl.load_workbook(book)
    return sum(1 for ws in wb.worksheets for row in ws.iter_rows() for c in row
               if isinstance(c.value, str) and c.value.startswith("="))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write the results to this file")
    ap.add_argument("--only", action="append", help="run only these cases")
    ap.add_argument("--templates", action="store_true",
                    help="also every bundled template at its default step")
    ap.add_argument("--runs", type=int, default=3,
                    help="runs per whole-process measurement (medians)")
    ap.add_argument("--issue", action="store_true",
                    help="only issue 42's table: verify, IronCalc, LibreOffice side by side")
    ap.add_argument("--against", type=Path,
                    help="with --issue: another checkout of linkbook, its verify timed too")
    opts = ap.parse_args()
    compile_tree(SRC)
    cases = dict(CASES)
    if opts.issue:          # before anything else: this process must stay small (measured)
        if opts.against is not None:
            compile_tree(opts.against / "src")
        results = issue_table(cases, opts.runs, opts.against,
                              bool(__import__("shutil").which("soffice")),
                              importlib.util.find_spec("ironcalc") is not None)
        print_issue(results, opts.runs)
        if opts.json:
            Path(opts.json).write_text(json.dumps(results, indent=2))
        return 0
    if opts.templates:
        cases.update({p.stem: (p.stem, []) for p in sorted((ROOT / "templates").glob("*.toml"))})
    have_office = bool(__import__("shutil").which("soffice"))
    have_ironcalc = importlib.util.find_spec("ironcalc") is not None
    results = {}
    seconds_per_cell = None    # ExcelModel cost, calibrated on the first case it runs
    with tempfile.TemporaryDirectory() as tmp:
        for case, (name, args) in cases.items():
            if opts.only and case not in opts.only:
                continue
            book = Path(tmp) / f"{case}.xlsx"
            r = {"build": run_job("build", name, args, book)}
            r["cells"] = formula_cells(book)
            r["vector"] = run_job("vector", name, args, book)
            predicted = seconds_per_cell * r["cells"] if seconds_per_cell else 0.0
            if "pump" in case and seconds_per_cell:
                predicted *= 20        # a grid cell is one ~1,000-character formula
            if predicted > EXCELMODEL_LIMIT_S:
                r["excelmodel"] = {"skipped": f"predicted {predicted:.0f} s"}
            else:
                # Uncalibrated (--only a pump case): the time limit still holds.
                r["excelmodel"] = run_job("excelmodel", name, args, book,
                                          timeout=EXCELMODEL_LIMIT_S)
                if "seconds" in r["excelmodel"] and "pump" not in case:
                    seconds_per_cell = r["excelmodel"]["seconds"] / r["cells"]
            r["office"] = run_job("office", name, args, book) if have_office else \
                {"skipped": "no soffice"}
            r["reference"] = run_job("reference", name, args, book)
            r["whole"] = whole_process(name, args, book, opts.runs, have_office, have_ironcalc)
            if "wall" in r["excelmodel"] and "seconds" in r["excelmodel"]:
                r["whole"]["excelmodel"] = r["excelmodel"]["wall"]
            results[case] = r
            print_row(case, r, flush=True)
    print_table(results)
    print_whole(results, opts.runs)
    if opts.json:
        Path(opts.json).write_text(json.dumps(results, indent=2))
    return 0


def _s(job: dict, key: str = "seconds") -> str:
    if "skipped" in job:
        return "skipped"
    if "error" in job:
        return "ERROR"
    return f"{job[key]:.2f}"


def print_row(case: str, r: dict, flush: bool = False) -> None:
    print(f"{case}: done ({r['cells']} formula cells)", file=sys.stderr, flush=flush)


def print_table(results: dict) -> None:
    head = (f"{'case':21} {'cells':>7} {'build':>7} {'vector':>7} {'peakMB':>7} {'Excel-':>9} "
            f"{'Libre-':>7} {'refer-':>7} {'ExcelModel/':>12} {'vector/':>8} {'verify':>7}")
    sub = (f"{'':21} {'':>7} {'[s]':>7} {'[s]':>7} {'':>7} {'Model [s]':>9} {'Office':>7} "
           f"{'ence [s]':>7} {'vector':>12} {'reference':>8} {'':>7}")
    print(head)
    print(sub)
    for case, r in results.items():
        vec, xl, ref = r["vector"], r["excelmodel"], r["reference"]
        ratio_xl = (f"{xl['seconds'] / vec['seconds']:.1f}x" if "seconds" in xl
                    and "seconds" in vec else "-")
        ratio_ref = (f"{vec['seconds'] / ref['seconds']:.1f}x" if "seconds" in ref
                     and "seconds" in vec else "-")
        verdict = "ok" if vec.get("ok") else "FAIL"
        print(f"{case:21} {r['cells']:7d} {_s(r['build']):>7} {_s(vec):>7} "
              f"{vec.get('peak_mb', 0):7.0f} {_s(xl):>9} {_s(r['office']):>7} {_s(ref):>7} "
              f"{ratio_xl:>12} {ratio_ref:>8} {verdict:>7}")
    print("\nSeconds of work in a process whose libraries are already loaded (the same warm-up for "
          "every job); vector wall = the whole `verify` process. peakMB: the vector verify "
          "process's peak resident memory. ratios: ExcelModel / vector, vector / reference.")
    for case, r in results.items():
        if "wall" in r["vector"]:
            print(f"  {case}: vector verify whole process {r['vector']['wall']:.2f} s")
    f1, f01 = results.get("fourbar-1"), results.get("fourbar-0.1")
    if f1 and f01 and "seconds" in f1["vector"] and "seconds" in f01["vector"]:
        print(f"0.1° / 1° four-bar vector verify: {f01['vector']['seconds'] / f1['vector']['seconds']:.1f}x"
              f" for {f01['cells'] / f1['cells']:.1f}x the cells")


def print_whole(results: dict, runs: int) -> None:
    tools = ("build", "verify", "office", "ironcalc", "excelmodel")
    print(f"\nWhole process, wall seconds, medians of {runs} runs (ExcelModel: one run)")
    print(f"{'case':21} " + "".join(f"{t:>11}" for t in tools)
          + f"{'office/verify':>15}{'verify/ironcalc':>17}{'excelmodel/verify':>19}")
    for case, r in results.items():
        w = r["whole"]
        cells = "".join(f"{w[t]:11.2f}" if t in w else f"{'-':>11}" for t in tools)

        def ratio(a, b, width):
            return f"{w[a] / w[b]:{width - 1}.2f}x" if a in w and b in w else f"{'-':>{width}}"
        print(f"{case:21} {cells}{ratio('office', 'verify', 15)}"
              f"{ratio('verify', 'ironcalc', 17)}{ratio('excelmodel', 'verify', 19)}")


if __name__ == "__main__":
    raise SystemExit(main())
