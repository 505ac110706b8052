"""`linkbook verify`: re-check a linkbook workbook against the independent reference.

The workbook says what it is (its build record: mechanism and layout); its inputs are read from
its own cells, so a book edited in Excel is verified with its new numbers. Every formula cell is
evaluated by an engine (or recalculated by an application) and judged against the reference
(judge.py); the values the book stores are judged too (stored.py). With the vector engine the
formulas are judged again at another set of inputs drawn from a seed (input_sets.py), where a
wrong term that vanishes at the book's own inputs shows. The parts: reading.py (the book and
its record), checks.py (the bounds and comparisons), judge.py with drawing.py, summary.py and
grid.py (the blocks), input_sets.py (the other inputs), report.py (the verdict).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..base.pause import gc_paused
from ..base.xlsx import forget_column_cells
from .checks import ABS_TOL, PER, TOLERANCE_RULE, Check, Mismatch, Rules
from .context import Reference
from .input_sets import DEFAULT_SEED, InputSet, input_cell, other_sets, write_inputs
from .judge import check_book, judge_book
from .reading import (RECORD_ERRORS, FormulaCells, UnusableFile, input_column, inputs_of,
                      mechanism_size, read_book, record_mismatch, stored_values)
from .report import Report, cell_ranges, cell_runs, likely_causes
from .stored import check_replaced, check_stored, not_formulas

# what the command, the package's face and the tests take from here
__all__ = ["ABS_TOL", "DEFAULT_SEED", "PER", "TOLERANCE_RULE", "Check", "Mismatch", "Reference",
           "Report", "UnusableFile", "cell_ranges", "cell_runs", "check_book", "inputs_of",
           "read_book", "record_mismatch", "verify", "report_of"]


@gc_paused
def verify(path: Path, engine: str = "vector", seed: int = DEFAULT_SEED) -> Report:
    """Every formula cell of the book at `path` compared with the independent reference, at
    the book's own inputs and (with the vector engine) at other input sets drawn from `seed`
    (input_sets.py). Raises UnusableFile with one line when the file cannot be verified."""
    wb, record = read_book(path)
    try:
        params = inputs_of(wb, record)    # first: an input no number holds is named, not computed
    except RECORD_ERRORS as exc:
        raise UnusableFile(record_mismatch(path, exc)) from None
    from ..engine import evaluator as engines
    rules = Rules(engines.is_error, engines.error_code)
    evaluation = None           # the engine that can evaluate the book at other inputs
    try:
        if engine == "vector":
            evaluation = engines.Engine(wb)
            values = evaluation.run_view()
        elif engine == "formulas":
            # ExcelModel rounds number constants to 15 decimals (engine.evaluate's
            # excel_model_constants): judged with the relative bound, as LibreOffice is
            values = engines.evaluate_formulas_model(path)
            rules = replace(rules, relative=True)
        else:
            # a real application (LibreOffice, Gnumeric) recalculates a copy: judged alike
            from ..engine import office
            if engine not in office.APPLICATIONS:
                raise UnusableFile(f"unknown engine {engine!r}")
            values = office.recalculated_values(path, engine)
            rules = Rules(office.is_error, office.error_code, relative=True)
    except engines.EngineError as exc:
        raise UnusableFile(f"{path}: {exc}") from None
    formulas = FormulaCells(wb)
    try:
        checks = judge_book(wb, record, values, rules)
        elsewhere, judged = formulas.judged(checks)
        replaced, absent = not_formulas(wb, elsewhere)
        if replaced:
            checks.append(check_replaced(wb, replaced))
        stored = stored_values(wb, path, judged)
        if stored:
            checks.append(check_stored(wb, record, values, stored, rules))
        count, unjudged = len(formulas), list(formulas.without(judged))
        # a cell's key each, a big book's largest dict: gone before the other sets are judged
        del stored
        sets = [] if evaluation is None else _judge_other_sets(
            wb, record, evaluation, rules, params, seed)
        return Report(str(path), record.mechanism, engine, checks, count, unjudged, params,
                      mechanism_size(record, params),
                      likely_causes(wb, checks + [c for s in sets for c in s.checks]),
                      sheets=list(wb.sheetnames), replaced=replaced, absent=absent,
                      seed=seed if evaluation is not None else None, input_sets=sets,
                      notes=list(getattr(wb, "notes", ())))
    except RECORD_ERRORS as exc:
        raise UnusableFile(record_mismatch(path, exc)) from None
    finally:
        forget_column_cells()
        if evaluation is not None:
            from ..engine.rerun import forget_places
            forget_places()


def _judge_other_sets(wb, record, evaluation, rules: Rules, params: dict, seed: int
                      ) -> list[InputSet]:
    """The other input sets of `seed`, each evaluated by the engine that evaluated the book
    (only what moves with the inputs and is judged, again: engine/rerun.py) and judged with
    the book's input cells holding it; the cells restored after."""
    from ..engine.errors import EngineError
    from ..engine.rerun import rerun
    solver = Reference(record)
    sweep = record.sweep
    angles = input_column(wb[sweep.sheet], "A", sweep.rows, solver.mechanism.input_is_angle)
    task = None
    if record.synthesis is not None:
        from .synthesis import task_inputs      # a synthesis book's: imported for those only
        task = task_inputs(wb, record)
    sets = other_sets(solver, record, params, angles, seed, task=task)
    for input_set in (s for s in sets if s.skipped is None):
        changed = {k: input_set.inputs[k] for k in input_set.changed}
        held = write_inputs(wb, record, changed)
        try:
            with rerun(evaluation, {input_cell(record, k): v
                                    for k, v in changed.items()}) as varied:
                input_set.checks = judge_book(wb, record, varied, rules, own_inputs=False)
        except (UnusableFile, EngineError) as exc:
            # what the book's own inputs do not meet (a grid's adjustment too small beside
            # the lengths drawn): that set is said not judged, the verdict is the book's own
            input_set.checks, input_set.skipped = [], " ".join(str(exc).split())
        finally:
            write_inputs(wb, record, held)
    return sets


def report_of(path, engine: str = "vector", seed: int | None = None) -> Report:
    """verify(), with a book that cannot be verified at all given as a Report of status 2 whose
    `error` is the one line that says why (the command prints it; the API returns it), so
    that a status is always there to act on. `seed` None: DEFAULT_SEED."""
    from ..base.safety import UnsafeFile
    from ..engine.errors import OfficeFailed, OfficeUnavailable
    try:
        return verify(Path(path), engine, DEFAULT_SEED if seed is None else seed)
    except (UnusableFile, UnsafeFile, OfficeUnavailable, OfficeFailed) as exc:
        said = " ".join(str(exc).split())
        if not said.startswith(f"{path}: "):    # among many books, each line names its own
            said = f"{path}: {said}"
        return Report(str(path), None, engine, [], error=said)
