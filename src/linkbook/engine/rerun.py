"""The values of a book the engine has evaluated, read where the engine holds them (Values: a
mapping like run()'s dict, without a copy of every cell), and the book evaluated again with
other values in some of its constant cells (rerun): what verify judges at its other input sets.

Only the formulas downstream of the changed cells can give other values, and of those only the
ones asked for are evaluated: a formula cell is evaluated when it is first looked up, with the
groups it needs, in the engine's order and by its own code (vector calls, running sums, cell by
cell), so each value is the one run() gives a book holding those inputs. A cell that does not
move with the inputs keeps run()'s value. Leaving the `with` block puts the book's own values
back into the engine, so it may rerun again with other inputs.
"""
from __future__ import annotations

import functools
from collections.abc import Iterator, Mapping
from contextlib import contextmanager

import numpy as np

from .adapter import public_value
from .errors import EngineError
from .order import closure, deps_and_downstream
from .references import cell_name
from ..base.xlsx import ColumnCells, coordinate_to_tuple, coordinates_to_arrays


@contextmanager
def rerun(engine, inputs: dict[tuple[str, str], object]) -> Iterator[Mapping]:
    """The values of every cell, as a mapping like run()'s, with the constant cells of `inputs`
    ((sheet, 'I7') -> value) holding those values. After run() only."""
    if not engine.groups and not engine.constants:
        raise EngineError("rerun follows run()")
    places = [engine._input_place(sheet, cell) for sheet, cell in inputs]
    kept = {sheet: grid.copy() for sheet, grid in engine.grid.items()}
    try:
        for (sheet, row, col), value in zip(places, inputs.values()):
            engine.grid[sheet][row, col] = value
        yield Rerun(engine, places)
    finally:
        engine.grid = kept


_FLOATS = {float, np.float64}

# A list of this many cells or fewer (a summary's cell, a check's few) is looked up cell by
# cell: the arrays' fixed cost is more than the lookups'.
FEW_CELLS = 4
# The places of a list of up to this many cells (a bundled book's column) are kept for the
# next lookup of the same cells; a longer column is read again (its reading is a small share
# of its work, and what it kept would be a big book's memory).
KEPT_CELLS = 256


def places(cells: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """coordinates_to_arrays(cells); a short list's kept until forget_places(): verify reads
    each column at the book's own inputs and again at each other input set."""
    if len(cells) > KEPT_CELLS or type(cells) is ColumnCells:    # the latter read no text
        return coordinates_to_arrays(cells)
    return _kept_places(tuple(cells))


def forget_places() -> None:
    """Let go of the kept places (at the end of a verify)."""
    _kept_places.cache_clear()


@functools.lru_cache(maxsize=512)
def _kept_places(cells: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
    rows, cols = coordinates_to_arrays(list(cells))
    rows.flags.writeable = cols.flags.writeable = False
    return rows, cols


class Values(Mapping):
    """(sheet, 'B7') -> value, as run()'s dict gives it, read from the engine's value grid as
    it stands (after run(); inside a rerun, that rerun's)."""

    def __init__(self, engine):
        self.engine = engine

    def _place(self, key) -> tuple[str, int, int] | None:
        """(sheet, row, col) of a cell of the value grid; None for any other key (run()'s
        dict has no value for it either)."""
        try:
            sheet, cell = key
            row, col = coordinate_to_tuple(cell)
            grid = self.engine.grid.get(sheet)
        except (TypeError, ValueError, AttributeError):
            return None
        if grid is None or row >= grid.shape[0] or col >= grid.shape[1]:
            return None
        return sheet, row, col

    def _ready(self, gids) -> None:
        """Make the groups `gids` hold their values (here they do: run() evaluated them)."""

    def __getitem__(self, key):
        place = self._place(key)
        if place is None:
            raise KeyError(key)
        sheet, row, col = place
        engine = self.engine
        gid = int(engine.owner[sheet][row, col])
        if gid < 0:
            if (row, col) not in engine.constants.get(sheet, {}):
                raise KeyError(key)         # an empty cell: run() gives none either
            return public_value(engine.grid[sheet][row, col], False)
        self._ready({gid})
        return public_value(engine.grid[sheet][row, col], True)

    def get(self, key, default=None):
        try:
            return self[key]
        except KeyError:
            return default

    def many(self, sheet: str, cells: list[str]) -> list:
        """[self.get((sheet, cell)) for cell in cells], looked up together (a column of a
        table: one lookup of the groups that own them)."""
        grid = self.engine.grid.get(sheet)
        try:
            rows, cols = (None, None) if len(cells) <= FEW_CELLS else places(cells)
        except (TypeError, ValueError):             # one that is no address
            grid = None
        if grid is None or rows is None:
            return [self.get((sheet, cell)) for cell in cells]
        inside = (rows < grid.shape[0]) & (cols < grid.shape[1])   # beyond: no value, None
        rows, cols = np.where(inside, rows, 0), np.where(inside, cols, 0)
        owners = np.where(inside, self.engine.owner[sheet][rows, cols], -1)
        self._ready(set(owners.tolist()) - {-1})
        values = self.engine.grid[sheet][rows, cols]
        if owners.min() >= 0 and set(map(type, values.tolist())) <= _FLOATS:
            return values.astype(float).tolist()      # formula numbers: floats, as public_value
        constants = self.engine.constants.get(sheet, {})
        return [public_value(v, True) if gid >= 0
                else public_value(v, False) if ok and (r, c) in constants else None
                for v, gid, r, c, ok in zip(values.tolist(), owners.tolist(), rows.tolist(),
                                            cols.tolist(), inside.tolist())]

    def __iter__(self):
        engine = self.engine
        for sheet, cells in engine.constants.items():
            for row, col in cells:
                yield sheet, cell_name(row, col)
        for g in engine.groups:
            for m in g.members:
                yield g.sheet, cell_name(m.row, m.col)

    def __len__(self) -> int:
        return sum(map(len, self.engine.constants.values())) + sum(
            len(g.members) for g in self.engine.groups)


class Rerun(Values):
    """Values of a book whose changed inputs the engine's grid holds; each formula downstream
    of them evaluated when first asked for."""

    def __init__(self, engine, places: list[tuple[str, int, int]]):
        super().__init__(engine)
        self.deps, self.moved = deps_and_downstream(engine.groups, engine.owner, places)
        self.done: set[int] = set()
        # each group's component's place in the engine's order
        self.place = {gid: k for k, component in enumerate(engine.order) for gid in component}

    def _ready(self, gids) -> None:
        waiting = (set(gids) & self.moved) - self.done
        if waiting:
            self._evaluate(waiting)

    def _evaluate(self, gids: set[int]) -> None:
        """Groups `gids` (moved, not yet evaluated) and what they need of the groups that
        moved, in the engine's order. What they need is found through the groups still to be
        evaluated only: a group that did not move reads none that did, and one evaluated
        already had what it needs evaluated with it."""
        need = closure(gids, self.deps, within=self.moved - self.done)
        order = self.engine.order
        with np.errstate(all="ignore"):
            for k in sorted({self.place[gid] for gid in need}):
                self.engine._evaluate_component(order[k])
                self.done.update(order[k])
