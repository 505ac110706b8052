"""A quantity's formula as the text of one cell: the model's keys resolved to defined names, to
the cells of the block the formula lands in, or inlined."""
from __future__ import annotations

import re

from ..base.errors import InputError
from ..base.xlsx import formula_problem
from ..language.excel import parenthesize, render
from ..language.model import Model

# A table's formula is rendered once for all its cells: a control character in it (style.ROW,
# grid.COL, motion.SWEEP_ROW) stands for a row number or a column's letters.
_PLACEHOLDER = re.compile("[\x00-\x1f]")
LAST_ROW = "1048576"
ABOVE_SUFFIX = "@above"   # {key@above}: the key's cell in the row above (excel.PLACEHOLDER)      # the longest a placeholder's text can be anywhere


class Resolver:
    """Turns a key into formula text for one place in the workbook.

    `names` maps parameters and constants to defined names; `cells` maps keys that have a cell in
    this block to its reference. Anything else that is an alias or a column is inlined.
    """

    def __init__(self, model: Model, names: dict[str, str], cells: dict[str, str],
                 field: str = "", place: str = LAST_ROW):
        self.model = model
        self.names = names
        self.cells = cells
        self.field = field      # the template field a formula beyond Excel's limits is named by
        self.place = place      # the longest text a placeholder stands for in this block
        self._by_key = {q.key: q for q in model.quantities}

    def __call__(self, key: str) -> str:
        if key in self.cells:
            return self.cells[key]
        if key.endswith(ABOVE_SUFFIX):    # no row above in this block: the step starts afresh
            return "NA()"
        if key in self.names:
            return self.names[key]
        q = self._by_key.get(key)
        if q is None:
            raise KeyError(f"formula refers to unknown symbol {{{key}}}")
        return parenthesize(render(q.formula, self))

    def formula(self, key: str) -> str:
        """The cell formula (with '=') of quantity `key` in this block; InputError naming the
        template field that made it where the cell would be beyond Excel's limits."""
        q = self._by_key[key]
        text = "=" + render(q.formula, self)
        problem = formula_problem(_PLACEHOLDER.sub(self.place, text[1:]))
        if problem:
            raise InputError(self.field or q.made_by or "mechanism",
                             f"the formula of {key} would be one {problem}")
        return text
