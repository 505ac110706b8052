"""A quantity's formula as the text of one cell: the model's keys resolved to defined names, to
the cells of the block the formula lands in, or inlined."""
from __future__ import annotations

from ..language.excel import parenthesize, render
from ..language.model import Model


class Resolver:
    """Turns a key into formula text for one place in the workbook.

    `names` maps parameters and constants to defined names; `cells` maps keys that have a cell in
    this block to its reference. Anything else that is an alias or a column is inlined.
    """

    def __init__(self, model: Model, names: dict[str, str], cells: dict[str, str]):
        self.model = model
        self.names = names
        self.cells = cells
        self._by_key = {q.key: q for q in model.quantities}

    def __call__(self, key: str) -> str:
        if key in self.cells:
            return self.cells[key]
        if key in self.names:
            return self.names[key]
        q = self._by_key.get(key)
        if q is None:
            raise KeyError(f"formula refers to unknown symbol {{{key}}}")
        return parenthesize(render(q.formula, self))

    def formula(self, key: str) -> str:
        """The cell formula (with '=') of quantity `key` in this block."""
        return "=" + render(self._by_key[key].formula, self)
