"""Wall time and peak memory of linkbook.engine.evaluator.evaluate() against formulas.ExcelModel.

Builds synthetic four-bar-like sweep tables (one angle column + 10 formula columns, named
parameters on a second sheet, a summary row with ranges) and prints, per size:
rows, formula cells, compiled shapes, evaluate() seconds and peak MB, ExcelModel seconds and
peak MB (ExcelModel is skipped above --model-max rows), and max |difference| between the two.

    python benchmarks/engine_probe.py                # 361 and 1441 rows (+3601, engine only)
    python benchmarks/engine_probe.py --rows 361 --model-max 0
"""
from __future__ import annotations

import argparse
import gc
import math
import sys
import tempfile
import time
import tracemalloc
from pathlib import Path

import openpyxl
from openpyxl.utils import get_column_letter
from openpyxl.workbook.defined_name import DefinedName

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
from linkbook.engine import evaluator as engine  # noqa: E402

PARAMS = {"a_1": 2.0, "a_2": 1.0, "a_3": 2.5, "a_4": 1.5, "branch": 1}
COLUMNS = [  # column letter -> formula for row {r}
    ("B", "=RADIANS(A{r})"),
    ("C", "=a_2*COS(B{r})-a_1"),
    ("D", "=a_2*SIN(B{r})"),
    ("E", "=SQRT(C{r}^2+D{r}^2)"),
    ("F", "=ATAN2(C{r},D{r})"),
    ("G", "=IFERROR(ACOS((a_3^2+a_4^2-E{r}^2)/(2*a_3*a_4)),NA())"),
    ("H", "=IFERROR(ACOS((a_4^2+E{r}^2-a_3^2)/(2*a_4*E{r})),NA())"),
    ("I", "=F{r}-branch*H{r}"),
    ("J", "=I{r}-branch*G{r}"),
    ("K", "=DEGREES(J{r})"),
]


def fourbar_book(rows: int) -> openpyxl.Workbook:
    """A 'Mechanism' sheet of named parameters and a 'Sweep' table of `rows` angles."""
    wb = openpyxl.Workbook()
    mech = wb.active
    mech.title = "Mechanism"
    for i, (name, value) in enumerate(PARAMS.items()):
        mech.cell(row=2 + i, column=1, value=name)
        mech.cell(row=2 + i, column=2, value=value)
        wb.defined_names[name] = DefinedName(name, attr_text=f"'Mechanism'!$B${2 + i}")
    sweep = wb.create_sheet("Sweep")
    first = 5
    for k in range(rows):
        r = first + k
        sweep[f"A{r}"] = 360.0 * k / (rows - 1)
        for letter, formula in COLUMNS:
            sweep[f"{letter}{r}"] = formula.format(r=r)
    last = first + rows - 1
    sweep["M2"] = f"=MAX(K{first}:K{last})-MIN(K{first}:K{last})"
    sweep["M3"] = f"=COUNT(G{first}:G{last})"
    return wb


def grid_book(rows: int, cols: int) -> openpyxl.Workbook:
    """Angles down column A, a coupler length across row 4, one loop-closure formula per cell
    (mixed references $A, C$4 and names), like a sweep-by-adjustment grid."""
    wb = fourbar_book(2)
    grid = wb.create_sheet("Grid")
    for j in range(cols):
        grid.cell(row=4, column=2 + j, value=1.0 + 2.0 * j / cols)
    for i in range(rows):
        r = 5 + i
        grid.cell(row=r, column=1, value=360.0 * i / (rows - 1))
        for j in range(cols):
            c = get_column_letter(2 + j)
            e = f"SQRT((a_2*COS(RADIANS($A{r}))-a_1)^2+(a_2*SIN(RADIANS($A{r})))^2)"
            grid.cell(row=r, column=2 + j, value=(
                f"=DEGREES(IFERROR(ACOS(({c}$4^2+a_4^2-{e}^2)/(2*{c}$4*a_4)),NA()))"))
    return wb


def measure(fn):
    """(result, seconds, peak MB): time without tracing, then memory in a traced rerun."""
    gc.collect()
    t0 = time.perf_counter()
    result = fn()
    seconds = time.perf_counter() - t0
    gc.collect()
    tracemalloc.start()
    fn()
    peak = tracemalloc.get_traced_memory()[1] / 2 ** 20
    tracemalloc.stop()
    return result, seconds, peak


def max_delta(a: dict, b: dict) -> float:
    worst = 0.0
    for key, x in b.items():
        y = a[key]
        if engine.is_error(x) or engine.is_error(y):
            assert engine.error_code(x) == engine.error_code(y), (key, x, y)
        elif isinstance(x, float) and isinstance(y, float) and not (math.isnan(x) or math.isnan(y)):
            worst = max(worst, abs(x - y))
        else:
            assert x == y, (key, x, y)
    return worst


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, nargs="*", default=[361, 1441, 3601])
    ap.add_argument("--model-max", type=int, default=1441,
                    help="run ExcelModel only up to this many rows (it is slow)")
    ap.add_argument("--grid", type=int, nargs=2, metavar=("ROWS", "COLS"), default=(361, 51),
                    help="also time a ROWS x COLS grid of one loop-closure formula (engine only)")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        warm = Path(tmp) / "warm.xlsx"
        fourbar_book(11).save(warm)
        t0 = time.perf_counter()
        engine.evaluate_file(warm)
        engine.evaluate_formulas_model(warm)
        print(f"(one-time import of formulas' function modules, not in the times below: "
              f"{time.perf_counter() - t0:.1f} s)")
        print(f"{'rows':>6} {'cells':>6} {'shapes':>6} {'evaluate s':>10} {'peak MB':>8} "
              f"{'ExcelModel s':>12} {'peak MB':>8} {'max |d|':>9}")
        for rows in args.rows:
            path = Path(tmp) / f"fourbar_{rows}.xlsx"
            fourbar_book(rows).save(path)
            wb = openpyxl.load_workbook(path)
            ours, t_ours, m_ours = measure(lambda: engine.Engine(wb).run())
            eng = engine.Engine(wb)
            eng.run()
            line = (f"{rows:>6} {eng.stats['formula_cells']:>6} {eng.stats['shapes']:>6} "
                    f"{t_ours:>10.2f} {m_ours:>8.1f}")
            if rows <= args.model_max:
                theirs, t_model, m_model = measure(lambda: engine.evaluate_formulas_model(path))
                line += f" {t_model:>12.1f} {m_model:>8.1f} {max_delta(ours, theirs):>9.1e}"
            else:
                line += f" {'skipped':>12} {'':>8} {'':>9}"
            print(line, flush=True)
        if args.grid:
            wb = grid_book(*args.grid)
            _, t_grid, m_grid = measure(lambda: engine.Engine(wb).run())
            print(f"grid {args.grid[0]}x{args.grid[1]} (one shape): evaluate {t_grid:.2f} s, "
                  f"peak {m_grid:.1f} MB")


if __name__ == "__main__":
    main()
