"""The verdict on one book: its checks, the formula cells none judged, the cells where each
chain of disagreement starts, and the cells named as ranges for the report's text."""
from __future__ import annotations

from dataclasses import dataclass, field

from .checks import STORED, Check, differing, judged_count, undetermined


@dataclass
class Report:
    """The verdict on one book: its checks, at its own inputs and at the other input sets."""
    path: str
    mechanism: str
    engine: str
    checks: list[Check]
    formula_cells: int = 0                    # in the whole book
    unjudged: list[tuple[str, str]] = field(default_factory=list)   # formula cells not compared
    inputs: dict[str, float] = field(default_factory=dict)          # as read from the book
    size: float = 0.0                         # S, the mechanism's size
    causes: set[tuple[str, str]] = field(default_factory=set)   # differing cells reading none
    sheets: list[str] = field(default_factory=list)  # the book's sheets in its tab order
    error: str | None = None        # why the book cannot be verified at all (status 2)
    # cells the build record holds formulas in that hold a constant instead
    replaced: list[tuple[str, str]] = field(default_factory=list)
    # cells the build record holds formulas in that are empty or on a sheet deleted (each
    # differs: it has no value)
    absent: list[tuple[str, str]] = field(default_factory=list)
    # what the file holds that leaves the numbers alone but a reader should hear of (a
    # built-in name an application wrote twice with other ranges)
    notes: list[str] = field(default_factory=list)
    # the seed the other input sets were drawn from (None: the book's own inputs only) and
    # those sets, each with its checks (input_sets.py)
    seed: int | None = None
    input_sets: list = field(default_factory=list)

    @property
    def disagrees(self) -> bool:
        return any(not c.ok for c in self.checks) or any(not s.ok for s in self.input_sets)

    @property
    def not_judged(self) -> list[tuple[str, str]]:
        """Cells too near a singular position to judge (Check.determines), each once: compared
        with the reference, but by a bound too wide to tell a wrong formula; a cell that
        differs elsewhere is counted there."""
        return sorted(undetermined(self.checks))

    @property
    def other_assembly(self) -> list[str]:
        """Where the book's method and the reference's continuation reach different
        assemblies (judge.note_other_assembly), one line a stretch of rows: named, not
        passed (the data do not say which assembly is meant)."""
        return [line for c in self.checks for line in c.assembly] + [
            f"input set {s.number}: {line}" for s in self.input_sets for c in s.checks
            for line in c.assembly]

    @property
    def ok(self) -> bool:
        return self.status == 0

    @property
    def status(self) -> int:
        """The exit status: 0 every formula cell agrees, 1 a cell disagrees, 2 some formula
        cells cannot be judged (the record does not say what they hold, they are too near a
        singular position, or the book's assembly differs from the reference's) and none
        disagrees, or the book cannot be verified at all."""
        if self.error is not None:
            return 2
        return 1 if self.disagrees else 2 if (self.unjudged or self.not_judged
                                              or self.other_assembly) else 0

    @property
    def cells(self) -> int:
        """Formula cells judged against the reference (each counted once; a constant where the
        record has a formula is judged, and differs, but is not a formula cell; a cell too near
        a singular position is not judged)."""
        return judged_count(self.checks, [*self.replaced, *self.absent, *self.not_judged])

    @property
    def stored_differ(self) -> int:
        """Formula cells whose stored value (what a reader that does not calculate shows)
        differs from the reference."""
        return sum(len(c.mismatches) for c in self.checks if c.block == STORED)

    @property
    def differing(self) -> int:
        """Cells that differ from the reference, at any input set (each counted once)."""
        return len(self.differing_cells().union(*(s.differing() for s in self.input_sets)))

    def differing_cells(self) -> set[tuple[str, str]]:
        """The cells that differ at the book's own inputs."""
        return differing(self.checks)

    @property
    def max_abs(self) -> float:
        """The largest difference from the reference, at the book's own inputs and at the
        other sets."""
        return max([c.max_abs for c in self.checks] + [s.max_abs for s in self.input_sets],
                   default=0.0)



def likely_causes(wb, checks: list[Check]) -> set[tuple[str, str]]:
    """The differing cells that read no other differing cell: where each chain of
    disagreement starts (a broken formula; the cells downstream differ because they read it)."""
    from ..engine import evaluator as engines
    from ..base.xlsx import coordinate_to_tuple
    differ = {(m.sheet, m.cell) for c in checks for m in c.mismatches}
    where: dict[str, set[tuple[int, int]]] = {}
    for sheet, cell in differ:
        where.setdefault(sheet, set()).add(coordinate_to_tuple(cell))

    def reads_a_differing_cell(key, rects) -> bool:
        me = (key[0], coordinate_to_tuple(key[1]))
        for sheet, top, left, bottom, right in rects:
            cells = where.get(sheet, set())
            if (bottom - top + 1) * (right - left + 1) <= len(cells):   # walk the smaller side
                hits = ((r, c) for r in range(top, bottom + 1) for c in range(left, right + 1)
                        if (r, c) in cells)
            else:
                hits = ((r, c) for r, c in cells if top <= r <= bottom and left <= c <= right)
            if any((sheet, rc) != me for rc in hits):
                return True
        return False
    # a cell on a sheet the edit deleted reads nothing: it is a cause itself
    reads = engines.cells_read(wb, {k for k in differ if k[0] in wb.sheetnames})
    return {key for key in differ if not reads_a_differing_cell(key, reads.get(key, []))}




def cell_ranges(cells: list[tuple[str, str]], most: int = 6) -> str:
    """'Sweep!F5:F77, Mechanism!I9' for sorted (sheet, cell) pairs: runs down a column joined;
    after `most` runs, how many more."""
    runs = cell_runs(cells)
    text = runs[:most]
    if len(runs) > most:
        text.append(f"and {len(runs) - most} more ranges")
    return ", ".join(text)


def cell_runs(cells: list[tuple[str, str]]) -> list[str]:
    """['Sweep!F5:F77', 'Mechanism!I9'] for sorted (sheet, cell) pairs: each run of rows down
    one column as one range."""
    from ..base.xlsx import column_letter, coordinate_to_tuple
    runs: list[list] = []
    for sheet, cell in cells:
        row, index = coordinate_to_tuple(cell)
        col = column_letter(index)
        last = runs[-1] if runs else None
        if last and last[0] == sheet and last[1] == col and last[3] == row - 1:
            last[3] = row
        else:
            runs.append([sheet, col, row, row])
    return [f"{s}!{c}{a}" if a == b else f"{s}!{c}{a}:{c}{b}" for s, c, a, b in runs]
