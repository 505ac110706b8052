"""The grouping of formula cells (engine/groups.py): whatever the walk that finds copies,
every group holds the cells of one shape and every shape is one group, as the lexer reads
each cell's formula on its own; the members row by row and the groups in the order a walk of
the sheet row by row meets them. Sheets of copied and edited formulas are drawn at random:
copies down a column and along a row, absolute and relative references, edited copies."""
from __future__ import annotations

import collections
import re

from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import examples
from linkbook.base import xlsx
from linkbook.engine.groups import Grouper
from linkbook.engine.references import References

# formulas written at (row 1, column 1) and shifted to their cells as a copy would shift them;
# some differ from another in their last character only
TEMPLATES = ["A1+1", "A1+2", "$A1*B$1", "SIN(A1)+$B$2", "A1+$B$1", "A1+$B$2", "C1-A1",
             "IF(A1>0,B1,NA())", "A1+A2+A3", "SUM(A1:B2)", "A1&\"x\"", "1+2"]


def shifted(template: str, rows: int, cols: int) -> str:
    """`template` copied `rows` down and `cols` right (relative references move)."""
    out, i = [], 0
    for m in re.finditer(r"(\$?)([A-Z]+)(\$?)([0-9]+)", template):
        col_abs, letters, row_abs, digits = m.groups()
        col = xlsx.column_index(letters) + (0 if col_abs else cols)
        row = int(digits) + (0 if row_abs else rows)
        out += [template[i:m.start()], col_abs, xlsx.column_letter(col), row_abs, str(row)]
        i = m.end()
    return "".join(out) + template[i:]


CELLS = st.dictionaries(
    st.tuples(st.integers(1, 12), st.integers(1, 5)),
    st.one_of(st.sampled_from(range(len(TEMPLATES))), st.just(-1)),
    min_size=1, max_size=40)


def sheet_of(cells: dict) -> xlsx.Worksheet:
    ws = xlsx.Worksheet("S")
    for (row, col), k in sorted(cells.items(), key=lambda item: (item[0][1], item[0][0])):
        if k == -1:
            text = shifted("A1+1", row - 1, col - 1) + "*2"   # an edited copy
        else:
            text = shifted(TEMPLATES[k], row - 1, col - 1)
        ws.held_columns.setdefault(col, xlsx.Column()).append(row, "=" + text, "f")
    return ws


def lexed_shape(refs: References, formula: str, row: int, col: int) -> str:
    return refs.fast_shape(formula, "S", row, col)[0]


@settings(max_examples=examples(150))
@given(cells=CELLS)
def test_every_group_is_one_shape_and_every_shape_one_group(cells):
    ws = sheet_of(cells)
    refs = References(["S"])
    grouper = Grouper(refs, collections.Counter())
    grouper.group(grouper.read_cells([ws]))
    seen, firsts = {}, []
    for g in grouper.groups:
        members = list(g.members)
        places = [(m.row, m.col) for m in members]
        assert places == sorted(places)                    # row by row
        firsts.append(places[0])
        shapes = {lexed_shape(refs, m.formula, m.row, m.col) for m in members}
        assert len(shapes) == 1, (g.shape, shapes)
        shape = shapes.pop()
        assert shape not in seen
        seen[shape] = g.gid
        for m in members:
            assert m.formula == ws.cell(m.row, m.col).value    # the cell's own text
    assert firsts == sorted(firsts)                        # groups as a row-by-row walk meets
    assert sorted(p for g in grouper.groups for p in zip(g.rows.tolist(), g.cols.tolist())) \
        == sorted(cells)
