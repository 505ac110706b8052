"""Fast evaluation of a workbook of live formulas, with the `formulas` package's own functions.

Method
------
1. *Shapes.* Every formula cell's text is rewritten with each reference in a relative form
   (R1C1: an offset for relative parts, a number for ``$`` parts, the sheet always explicit; a
   workbook-scoped defined name becomes the absolute reference to its target).  In C8,
   ``=A8*COS(B8)-$D$2+E$7`` has the shape ``='S'!R[0]C[-2]*COS('S'!R[0]C[-1])-'S'!R2C4+'S'!R7C[2]``.
   Cells of one sheet with one shape form a *group*: a column of a sweep table is one group.
   References are found by a regex lexer (fast), and for every group the parser re-reads the
   first member: if its references are not exactly the lexer's spans, every member of that group
   is re-read by the parser (slow but exact).  The parser is linkbook.grammar, which reads the
   grammar linkbook writes into the graph `formulas`' parser would make, node for node, in a
   fraction of its time; for any formula outside that grammar it is `formulas`' own parser.
2. *One compile per group.* The parsed graph of a representative member, compiled.
   The compiled function's inputs (``'E5'``, ``'SWEEP!B5:B40'``, ``'A_3'``) are tied to the
   reference descriptors of the shape (and checked against the ranges `formulas` resolved), so
   any member's inputs are the descriptors shifted to that member.  The representative is the
   first member unless two descriptors share one input there (``=B5+$B$5`` in row 5): then a
   member where they do not (row 6) is compiled instead.  "Compiled" means a _Pipe: the parsed
   graph's function nodes (formulas' own functions) called in dependency order, without
   schedula's dispatcher; only a graph with operators on references or impure functions goes
   through ``compile()``.  With ``only`` (cells wanted), the groups those cells do not need,
   by the references of the shapes, are dropped before anything is compiled, and a sheet is
   grouped only when a needed group reads it.
3. *Order.* A group depends on the groups owning the cells it reads.  Groups are evaluated in
   topological order of their strongly connected components; a group that reads itself (a running
   column) or a cycle of groups is evaluated cell by cell in cell-level topological order.
4. *Modes.*
   - ``vector``: single-cell inputs only, functions from ELEMENTWISE and ROW_BY_ROW only.  The
     function is called once with an (n, 1) object array per input.  Each node of the compiled
     graph is wrapped: element-wise functions (arithmetic, COS, ATAN2, IF, IFERROR, ...) run on
     the whole array; other nodes (MAX of two cells, AND, ...), and an element-wise node whose
     output collapsed (``formulas`` turns an exception such as an overflow into one #VALUE! for
     the whole call), run row by row on (1, 1) slices, which is exactly what a per-cell call does.
     Arithmetic and the common math functions (NUMERIC_FORMS) first run as float-array
     operations on the rows whose arguments are finite numbers, giving the bits formulas' own
     per-element call gives; the other rows (errors, text, EMPTY, non-finite results) go through
     formulas' function.
   - ``cell``: ranges or other functions (ROWS, INDEX, SMALL, ``:``, ...).  The group's one
     compiled function is called per member with `formulas` Ranges inputs, as ExcelModel does.
   - ``each``: functions that read the host cell (ROW(), COLUMN(), ``@``), or inputs that are not
     one reference (unions, intersections): every member is compiled on its own with its host
     cell, like ExcelModel.
5. *Values* follow ExcelModel: an empty cell is ``sh.EMPTY`` (functions treat it as 0 / ""), a
   result that is EMPTY becomes 0, numeric constants are what the saved file holds (openpyxl writes
   ``%.16g``) rounded to 15 decimals, errors are `formulas` XlError objects (#N/A, #NUM!, ...).

Limits (they raise UnsupportedFormulaError rather than guess): INDIRECT, OFFSET, ISFORMULA,
FORMULATEXT, CELL, spill/anchor references, whole-column/row ranges (A:A, 1:1), R1C1 text,
external books, unknown sheets or names, sheet-scoped names, names that are not a cell or range
reference, multi-cell array formulas, data-table formulas.  Circular references raise
CircularReferenceError.  Dates are passed through as openpyxl returns them.  A self-reading group
that reads itself through ranges (``=SUM($C$5:C7)`` in column C) costs O(n^2) to order.
"""
from __future__ import annotations

import contextlib
import functools
import graphlib
import io
import itertools
import math
import re
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import schedula as sh
from formulas.errors import AnchorRangeName, InvalidRangeName
from formulas.functions import (COMPILING, FUNCTIONS, Array, flatten, get_functions,
                                is_number, parse_ranges, replace_empty, wrap_func)
from formulas.functions.operators import OPERATORS
from formulas.ranges import Ranges
from formulas.tokens.function import Function
from formulas.tokens.operand import Error, Range, XlError
from formulas.tokens.operator import Intersect, OperatorToken

from . import grammar
from ..base.xlsx import column_index, column_letter, coordinate_to_tuple

__all__ = [
    "evaluate", "evaluate_file", "evaluate_formulas_model", "is_error", "error_code", "shape_of",
    "Engine",
    "EngineError", "UnsupportedFormulaError", "CircularReferenceError",
]

MAX_ROW, MAX_COL = 1048576, 16384

# Functions whose compiled node maps (n, 1) arrays element by element exactly as it maps (1, 1)
# arrays (checked against per-cell calls over numbers, bools, strings, EMPTY and errors in
# tests/test_engine.py).  Every other node runs row by row in vector mode.
ELEMENTWISE = frozenset("""
    ABS ACOS ACOSH ASIN ASINH ATAN ATAN2 ATANH CHOOSE COS COSH COT CSC DEGREES EVEN EXP IF
    IFERROR IFNA INT ISBLANK ISERR ISERROR ISNA ISNUMBER ISTEXT LN LOG LOG10 MOD NA NOT ODD PI
    POWER RADIANS ROUND ROUNDDOWN ROUNDUP SEC SIGN SIN SINH SQRT TAN TANH TRUNC
    + - * / ^ & = <> < > <= >= u- u+ % bypass
""".split())
# Functions that give one value for scalar arguments but do not map arrays element-wise (MAX
# aggregates them): in vector mode their nodes run row by row.  Anything outside ELEMENTWISE and
# ROW_BY_ROW (ranges-aware ROWS/INDEX, array makers such as {1,2,3} or SEQUENCE, ...) puts its
# group in cell mode, so that no array that merely has n elements is taken for n rows.
ROW_BY_ROW = frozenset("""
    AND AVERAGE CEILING CONCAT CONCATENATE COUNT COUNTA EXACT FACT FALSE FIND FLOOR LEFT LEN
    LOWER MAX MEDIAN MID MIN N OR PRODUCT RIGHT SEARCH SQRTPI SUBSTITUTE SUM SUMSQ TEXT TRIM TRUE
    UPPER VALUE XOR
""".split())
VECTOR_SAFE = ELEMENTWISE | ROW_BY_ROW
# Functions that read the host cell (the compiled graph has the CELL input).
HOST_AWARE = frozenset({"ROW", "COLUMN", "SINGLE", "_XLFN.SINGLE", "@"})
# Functions whose result depends on cells that are not among the compiled inputs.
DYNAMIC = frozenset({"INDIRECT", "OFFSET", "ISFORMULA", "_XLFN.ISFORMULA", "FORMULATEXT",
                     "_XLFN.FORMULATEXT", "CELL"})



class _OnUse:
    """Stands for a scipy module (or one of its functions) until first used, then imports it."""

    def __init__(self, module: str, attribute: str | None = None):
        self._module, self._attribute = module, attribute

    def _real(self):
        import importlib
        real = importlib.import_module(self._module)
        return getattr(real, self._attribute) if self._attribute else real

    def __getattr__(self, name):
        return getattr(self._real(), name)

    def __call__(self, *args, **kwargs):
        return self._real()(*args, **kwargs)


def _import_function_modules_lightly() -> None:
    """`formulas` gets any function (COS as much as MAX) through get_functions(), which imports
    all its function modules; its statistics module imports scipy at its top (about a second
    of start-up, ahead of any book's first formula) for functions no linkbook book uses, and its
    math module reads numpy.random (RAND) at its top, which imports numpy.random (about 15 ms).
    They are imported here with scipy and numpy.random standing in: the same functions, and the
    real module imported the first time one of them needs it."""
    import sys
    import types
    name = "formulas.functions.stat"
    if name in sys.modules or "scipy" in sys.modules:
        return
    scipy = types.ModuleType("scipy")
    scipy.__path__ = []
    scipy.stats, scipy.linalg = _OnUse("scipy.stats"), _OnUse("scipy.linalg")
    interpolate = types.ModuleType("scipy.interpolate")
    interpolate.interp1d = _OnUse("scipy.interpolate", "interp1d")
    sys.modules["scipy"], sys.modules["scipy.interpolate"] = scipy, interpolate
    random_stand_in = None
    if "numpy.random" not in sys.modules:      # numpy 2 imports it on first use, 1.26 at once
        random_stand_in = types.ModuleType("numpy.random")

        def rand(*args):        # a function, so that functools.wraps finds its name
            import numpy.random
            return numpy.random.rand(*args)
        random_stand_in.rand = rand
        np.random = random_stand_in
    try:
        import importlib
        importlib.import_module(name)
        importlib.import_module("formulas.functions.math")
    finally:
        del sys.modules["scipy"], sys.modules["scipy.interpolate"]
        if random_stand_in is not None and np.__dict__.get("random") is random_stand_in:
            del np.random       # numpy's own lazy attribute again (unless the real module
                                # was imported meanwhile and took its place)


_import_function_modules_lightly()


def _aggregate(function_num, options, ref, *k):
    """Excel 2010's AGGREGATE, which `formulas` lacks, in the forms a workbook needs to skip
    the #N/A rows of a column: MAX (4), MIN (5), LARGE (14, k), SMALL (15, k) with option 6
    (ignore error values). Any other function or option gives #VALUE! (not evaluated here)."""
    def scalar(x):
        return np.ravel(x)[0] if isinstance(x, np.ndarray) else x
    num, opt = scalar(function_num), scalar(options)
    if opt != 6 or num not in (4, 5, 14, 15) or (num >= 14) != (len(k) == 1):
        return Error.errors["#VALUE!"]
    numbers = sorted(float(v) for v in flatten(ref, check=None)
                     if isinstance(v, (int, float, np.number))
                     and not isinstance(v, (bool, np.bool_, XlError)))
    if num in (4, 5):
        return (numbers[-1] if num == 4 else numbers[0]) if numbers else 0.0
    rank = scalar(k[0])
    if not isinstance(rank, (int, float)) or not 1 <= rank <= len(numbers):
        return Error.errors["#NUM!"]
    i = math.ceil(rank) - 1
    return numbers[-1 - i] if num == 14 else numbers[i]


def _register(names, func) -> None:
    """Add a function to `formulas`: to the table its get_functions() copies on first use, and
    to that copy if someone has already made it (without making it: that imports scipy)."""
    for name in names:
        FUNCTIONS[name] = func
        if get_functions.cache_info().currsize:
            get_functions()[name] = func


_register(("AGGREGATE", "_XLFN.AGGREGATE"), wrap_func(_aggregate))


def _cell_token():
    """The input by which formulas gives a host-reading function (ROW, CELL) its cell; imported
    where needed, as formulas.cell imports the parser."""
    from formulas.cell import CELL
    return CELL


@functools.lru_cache(maxsize=1)
def _parser():
    """formulas' parser, imported on first use: linkbook.grammar reads what linkbook writes, and
    the parser's modules take a tenth of a second to import."""
    from formulas import Parser
    return Parser()

# Compiled functions by (sheet, skeleton, pattern of equal references, mode): see _compiled.
_COMPILED: dict[tuple, tuple[object, list[int], "_Batch"]] = {}
# Skeletons whose references the `formulas` tokenizer has been seen to read exactly as the
# lexer does, with the functions they call: a formula of a known skeleton is not re-tokenized.
_READ_SKELETONS: dict[str, set[str]] = {}
_COMPILED_MAX = 2048


class EngineError(Exception):
    """The engine cannot evaluate this workbook."""


class UnsupportedFormulaError(EngineError):
    """A formula uses something outside the engine's documented limits."""


class CircularReferenceError(EngineError):
    """Formula cells read each other in a cycle."""


# --------------------------------------------------------------------------- public API

def evaluate(wb, only=None,
             excel_model_constants: bool = False) -> dict[tuple[str, str], object]:
    """Value of every non-empty cell of every worksheet, keyed by (sheet title, 'B7').

    Formula cells get a float, a `formulas` XlError (#N/A, #NUM!, #DIV/0!, ...), or a str/bool
    where the formula yields one; constants keep their type (ints stay ints).  `only`: cells
    ((sheet title, 'B7')) whose values are wanted: then only the formulas they need, directly
    or not, are evaluated, and the result holds those formula cells and every constant of the
    sheets they read (other sheets are not read at all). Number
    constants are read as the double the file holds, as Excel and LibreOffice read them;
    `excel_model_constants` rounds them to 15 decimals first, as formulas.ExcelModel does (which
    loses digits of small numbers: 1.2345678901234e-5 becomes 1.2345678901e-5), for bit-for-bit
    comparisons with it."""
    return Engine(wb, only=only, excel_model_constants=excel_model_constants).run()


def vary(wb, cell: tuple[str, str], inputs, read) -> Iterator[dict]:
    """For each value of `inputs` put into the input cell `cell` ((sheet title, 'I7')): the
    values (as evaluate() gives them) of the cells in `read`. The book is evaluated once; then
    only the formulas downstream of the input cell are evaluated again for each value."""
    return Engine(wb).vary(cell[0], cell[1], inputs, read)


def evaluate_file(path, excel_model_constants: bool = False) -> dict[tuple[str, str], object]:
    """evaluate() of the workbook at `path`, loaded with its formulas (not data_only)."""
    import openpyxl
    return evaluate(openpyxl.load_workbook(path, data_only=False),
                    excel_model_constants=excel_model_constants)


def shape_of(formula: str, cell: str, sheet: str = "Sheet", wb=None) -> str:
    """The shape of `formula` written in `cell` ('C8') of `sheet`: every reference in R1C1 form
    with its sheet, names of `wb` replaced by their targets.  Found by the `formulas` tokenizer."""
    refs = References.of(wb) if wb is not None else References([sheet])
    row, col = coordinate_to_tuple(cell)
    return _shape(formula, _tokenize(formula).spans, refs, refs.sheet(sheet), row, col)[0]


def is_error(value) -> bool:
    return isinstance(value, XlError)


def error_code(value) -> str | None:
    """'#N/A', '#NUM!', ... for an error value, else None."""
    return str(value) if isinstance(value, XlError) else None


def evaluate_formulas_model(path) -> dict[tuple[str, str], object]:
    """The same dict as evaluate_file(), computed by the slow full-fidelity formulas.ExcelModel.

    ExcelModel's keys ("'[book.xlsx]SHEET'!A1", sheet upper-cased) become ('Sheet', 'A1'); its
    1x1 Ranges become scalars; names, ranges and referenced-but-empty cells are left out.  Note
    (formulas 1.3.4): a reference to a sheet whose name holds an apostrophe gives #REF! here."""
    import formulas
    path = str(Path(path).resolve())
    with contextlib.redirect_stderr(io.StringIO()):  # ExcelModel.finish() draws a tqdm bar
        solution = formulas.ExcelModel().loads(path).finish().calculate()
    import openpyxl
    book = openpyxl.load_workbook(path, data_only=False)
    titles = {ws.title.upper(): ws.title for ws in book.worksheets}
    formula_cells = {(ws.title, c.coordinate) for ws in book.worksheets
                     for c in ws._cells.values() if c.data_type == "f"}
    out = {}
    for key, value in solution.items():
        cell = _model_key(key, titles)
        if cell is None:
            continue
        if isinstance(value, Ranges):
            value = value.value
        if isinstance(value, np.ndarray):
            if value.size != 1:
                continue
            value = value.reshape(-1)[0]
        if value is sh.EMPTY:
            continue  # a referenced empty cell, not a cell of the book
        out[cell] = _public_value(value, cell in formula_cells)
    return out


_MODEL_KEY = re.compile(r"^'\[[^\]]*\](?P<sheet>.*)'!(?P<ref>[A-Z]{1,3}[0-9]+)$", re.S)


def _model_key(key, titles: dict[str, str]) -> tuple[str, str] | None:
    """("'[book.xlsx]SHEET'!A1") -> ('Sheet', 'A1'); None for names, ranges and tokens."""
    if not isinstance(key, str) or isinstance(key, sh.Token):
        return None
    m = _MODEL_KEY.match(key)
    if not m:
        return None
    title = titles.get(m["sheet"].replace("''", "'"))
    return (title, m["ref"]) if title else None


def _public_value(value, is_formula: bool):
    """numpy scalars -> Python; formula numbers -> float; errors, str, bool unchanged."""
    if isinstance(value, XlError):
        return value
    if value is sh.EMPTY:
        return 0.0 if is_formula else None
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, np.generic):
        value = value.item()
    if is_formula and isinstance(value, (int, float)) and not isinstance(value, bool):
        return float(value)
    return value


# --------------------------------------------------------------------------- references

@dataclass(frozen=True)
class RefDesc:
    """One reference of a shape.  A coordinate is absolute where its flag is set, else an
    offset from the host cell.  Names are all-absolute descriptors of their target."""
    sheet: str
    r1: int
    c1: int
    r2: int
    c2: int
    ar1: bool
    ac1: bool
    ar2: bool
    ac2: bool
    is_range: bool

    def canonical(self) -> str:
        def part(v, absolute, letter):
            return f"{letter}{v}" if absolute else f"{letter}[{v}]"
        first = part(self.r1, self.ar1, "R") + part(self.c1, self.ac1, "C")
        if self.is_range:
            first += ":" + part(self.r2, self.ar2, "R") + part(self.c2, self.ac2, "C")
        return f"'{self.sheet}'!{first}"

    @property
    def is_absolute(self) -> bool:
        return self.ar1 and self.ac1 and self.ar2 and self.ac2

    def at(self, rows, cols):
        """(r1, c1, r2, c2) for host cell(s); works on ints and on numpy arrays."""
        r1 = self.r1 if self.ar1 else rows + self.r1
        c1 = self.c1 if self.ac1 else cols + self.c1
        r2 = self.r2 if self.ar2 else rows + self.r2
        c2 = self.c2 if self.ac2 else cols + self.c2
        return r1, c1, r2, c2

    def rect(self, row: int, col: int) -> tuple[str, int, int, int, int]:
        """(sheet, top, left, bottom, right) for one host cell."""
        r1, c1, r2, c2 = self.at(row, col)
        return self.sheet, min(r1, r2), min(c1, c2), max(r1, r2), max(c1, c2)


# Fast lexer: strings, errors and numbers are consumed whole so that "E1" in 1E-12 or "LOG10(" is
# never a reference; every identifier is consumed whole (a function if followed by "(").
# Possessive quantifiers and the leading lookahead only make it faster (no backtracking).
_LEXER = re.compile(r"""
  (?=["\#'$\w.])
  (?:
    (?P<string>"(?:[^"]|"")*+")
  | (?P<error>\#(?:NULL!|DIV/0!|VALUE!|REF!|NUM!|NAME\?|N/A|GETTING_DATA))
  | (?P<ref>(?:(?P<sheet>'(?:[^']|'')++'|[^\W\d][\w.]*+)!)?
        (?P<ca>\$?)(?P<c>[A-Za-z]{1,3})(?P<ra>\$?)(?P<r>[0-9]++)
        (?::(?P<cb>\$?)(?P<c2>[A-Za-z]{1,3})(?P<rb>\$?)(?P<r2>[0-9]++))?
    )(?![\w.(!:$\#\[])
  | (?P<number>(?:[0-9]++(?:\.[0-9]*+)?|\.[0-9]++)(?:[eE][+-]?[0-9]++)?)
  | (?P<ident>[^\W\d][\w.]*+)(?P<call>\s*\()?
  )
""", re.X)
_REF_TEXT = re.compile(r"""^(?:(?P<sheet>'(?:[^']|'')+'|[^\W\d][\w.]*)!)?
    (?P<ca>\$?)(?P<c>[A-Za-z]{1,3})(?P<ra>\$?)(?P<r>[0-9]+)
    (?::(?P<cb>\$?)(?P<c2>[A-Za-z]{1,3})(?P<rb>\$?)(?P<r2>[0-9]+))?$""", re.X)
_NAME_TEXT = re.compile(r"^[^\W\d][\w.]*$")


@functools.lru_cache(maxsize=65536)
def _parse_a1(text: str):
    """'Sheet'!$B5:C$7 -> (sheet text or None, (row, col, row_abs, col_abs) x 1 or 2), or None."""
    m = _REF_TEXT.match(text)
    if not m:
        return None
    sheet = m["sheet"]
    if sheet and sheet.startswith("'"):
        sheet = sheet[1:-1].replace("''", "'")
    corners = [(int(m["r"]), column_index(m["c"]), bool(m["ra"]), bool(m["ca"]))]
    if m["c2"]:
        corners.append((int(m["r2"]), column_index(m["c2"]), bool(m["rb"]), bool(m["cb"])))
    for row, col, _, _ in corners:
        if not (1 <= row <= MAX_ROW and 1 <= col <= MAX_COL):
            return None
    return sheet, tuple(corners)


def _rc(digits: str, absolute: str, host: int, letter: str) -> str:
    value = int(digits)
    if not 1 <= value <= MAX_ROW:
        raise UnsupportedFormulaError(f"row {digits} out of range")
    return f"{letter}{value}" if absolute else f"{letter}[{value - host}]"


def _rc_col(letters: str, absolute: str, host: int) -> str:
    value = column_index(letters)
    if value > MAX_COL:
        raise UnsupportedFormulaError(f"column {letters} out of range")
    return f"C{value}" if absolute else f"C[{value - host}]"


@dataclass(frozen=True)
class Template:
    """A formula as literal chunks around the row numbers and column letters of its references,
    so that the formula of a copied cell is found by shifting the relative ones (no lexing)."""
    chunks: tuple[str, ...]
    slots: tuple[tuple[bool, int, bool], ...]   # (is_row, value, relative)

    @functools.cached_property
    def _relative(self) -> tuple[tuple[str, ...], tuple[tuple[bool, int], ...]]:
        """The text between relative slots (absolute numbers written in), and those slots."""
        texts, slots, text = [], [], self.chunks[0]
        for (is_row, value, relative), chunk in zip(self.slots, self.chunks[1:]):
            if relative:
                texts.append(text)
                slots.append((is_row, value))
                text = chunk
            else:
                text += (str(value) if is_row else column_letter(value)) + chunk
        texts.append(text)
        return tuple(texts), tuple(slots)

    @functools.cached_property
    def _down(self) -> tuple[tuple[str, ...], tuple[int, ...]]:
        """_relative with its column slots written in: the text between relative rows, and
        those rows (a copy down the column moves only them)."""
        texts, slots = self._relative
        out, rows, text = [], [], texts[0]
        for (is_row, value), chunk in zip(slots, texts[1:]):
            if is_row:
                out.append(text)
                rows.append(value)
                text = chunk
            else:
                text += column_letter(value) + chunk
        out.append(text)
        return tuple(out), tuple(rows)

    def shifted(self, dr: int, dc: int) -> str | None:
        """The text of this formula copied dr rows down and dc columns right (None if a
        reference would leave the sheet)."""
        if dc == 0:
            texts, rows = self._down
            out = [texts[0]]
            for value, text in zip(rows, texts[1:]):
                value += dr
                if not 1 <= value <= MAX_ROW:
                    return None
                out += (str(value), text)
            return "".join(out)
        texts, slots = self._relative
        out = [texts[0]]
        for (is_row, value), text in zip(slots, texts[1:]):
            if is_row:
                value += dr
                if not 1 <= value <= MAX_ROW:
                    return None
                out += (str(value), text)
            else:
                value += dc
                if not 1 <= value <= MAX_COL:
                    return None
                out += (column_letter(value), text)
        return "".join(out)


class References:
    """Resolves reference texts and defined names of one workbook to RefDesc."""

    def __init__(self, titles, names: dict[str, str] | None = None):
        self.titles = {t.upper(): t for t in titles}
        self.names = {k.upper(): v for k, v in (names or {}).items()}   # NAME -> "'S'!$C$6"

    @classmethod
    def of(cls, wb) -> "References":
        return cls([ws.title for ws in wb.worksheets], dict(_global_names(wb)))

    def sheet(self, text: str) -> str:
        title = self.titles.get(text.upper())
        if title is None:
            raise UnsupportedFormulaError(f"the sheet {text!r} does not exist in the workbook")
        return title

    def is_name(self, ident: str) -> bool:
        return ident.upper() in self.names

    @functools.lru_cache(maxsize=None)
    def name(self, ident: str) -> RefDesc:
        text = self.names.get(ident.upper())
        parsed = _parse_a1(text.strip().lstrip("=")) if text else None
        if parsed is None or parsed[0] is None:
            raise UnsupportedFormulaError(
                f"defined name {ident!r} is not a sheet-qualified cell or range ({text!r})")
        return self._desc(parsed, 0, 0, absolute=True)

    @functools.lru_cache(maxsize=None)
    def name_shape(self, ident: str) -> str:
        return self.name(ident).canonical()

    def ref(self, text: str, host_sheet: str, row: int, col: int) -> RefDesc:
        """Descriptor of one reference text (A1 reference or defined name) in a host cell."""
        parsed = _parse_a1(text)
        if parsed is None:
            if _NAME_TEXT.match(text) and self.is_name(text):
                return self.name(text)
            if _NAME_TEXT.match(text):
                raise UnsupportedFormulaError(f"the name {text} is not defined in the workbook")
            raise UnsupportedFormulaError(f"the reference {text!r} (a whole row or column, or "
                                          "not a cell or range) cannot be evaluated here")
        sheet = self.sheet(parsed[0]) if parsed[0] is not None else host_sheet
        return self._desc((sheet, parsed[1]), row, col)

    @functools.lru_cache(maxsize=None)
    def sheet_text(self, text: str) -> str:
        """Title of a sheet as written before '!' (quoted or not)."""
        if text.startswith("'"):
            text = text[1:-1].replace("''", "'")
        return self.sheet(text)

    def fast_shape(self, formula: str, sheet: str, row: int, col: int):
        """(shape, Template) from the regex lexer alone: the per-cell hot path.  The shape must
        equal _shape() over the tokenizer's spans; Engine._group checks one cell per group."""
        parts, chunks, slots, pos, cut = [], [], [], 0, 0
        for m in _LEXER.finditer(formula):
            kind = m.lastgroup
            if kind == "ref":
                title = self.sheet_text(m["sheet"]) if m["sheet"] else sheet
                ref = _rc(m["r"], m["ra"], row, "R") + _rc_col(m["c"], m["ca"], col)
                corners = [("c", "ca"), ("r", "ra")]
                if m["c2"]:
                    ref += ":" + _rc(m["r2"], m["rb"], row, "R") + _rc_col(m["c2"], m["cb"], col)
                    corners += [("c2", "cb"), ("r2", "rb")]
                start, end = m.span("ref")
                parts += [formula[pos:start], f"'{title}'!", ref]
                pos = end
                for group, dollar in corners:  # the numbers a copy of this cell would change
                    a, b = m.span(group)
                    is_row = group[0] == "r"
                    value = int(m[group]) if is_row else column_index(m[group])
                    chunks.append(formula[cut:a])
                    slots.append((is_row, value, not m[dollar]))
                    cut = b
            elif kind == "ident" and self.is_name(m["ident"]):
                start, end = m.span("ident")
                parts += [formula[pos:start], self.name_shape(m["ident"])]
                pos = end
        parts.append(formula[pos:])
        chunks.append(formula[cut:])
        return "".join(parts), Template(tuple(chunks), tuple(slots))

    def _desc(self, parsed, row, col, absolute=False) -> RefDesc:
        sheet, corners = parsed
        sheet = self.sheet(sheet)
        (r1, c1, ar1, ac1) = corners[0]
        (r2, c2, ar2, ac2) = corners[-1]
        if absolute:
            ar1 = ac1 = ar2 = ac2 = True
        return RefDesc(sheet, r1 if ar1 else r1 - row, c1 if ac1 else c1 - col,
                       r2 if ar2 else r2 - row, c2 if ac2 else c2 - col,
                       ar1, ac1, ar2, ac2, len(corners) == 2)


def _global_names(wb):
    """(name, reference text) of visible workbook-scoped names, as ExcelModel reads them."""
    names = wb.defined_names
    items = names.items() if hasattr(names, "items") else ((d.name, d) for d in names)
    for name, dn in items:
        if getattr(dn, "hidden", False) or getattr(dn, "localSheetId", None) is not None:
            continue
        yield name, dn.attr_text


# --------------------------------------------------------------------------- formula reading

def _lex_spans(formula: str, refs: References) -> list[tuple[int, int]]:
    """Spans of references and defined names found by the regex lexer."""
    spans = []
    for m in _LEXER.finditer(formula):
        if m["ref"] is not None:
            spans.append(m.span("ref"))
        elif m["ident"] is not None and m["call"] is None and refs.is_name(m["ident"]):
            spans.append(m.span("ident"))
    return spans


@dataclass
class TokenInfo:
    """What the `formulas` tokenizer says about one formula."""
    spans: list[tuple[int, int]]
    keys: list[str]            # Range token names, e.g. 'SWEEP!D8', 'A_3' (the compiled inputs)
    functions: set[str]
    builder: object


def _tokenize(formula: str) -> TokenInfo:
    """References, keys and functions of a formula, with its graph: linkbook.grammar's reading
    where the formula is in that grammar, else `formulas`' parser's."""
    parsed = grammar.parse(formula, _plain_functions())
    if parsed is not None:
        info = TokenInfo(parsed.spans, parsed.keys, set(parsed.functions), parsed)
    else:
        info = _formulas_tokenize(formula)
    bad = info.functions & DYNAMIC
    if bad:
        raise UnsupportedFormulaError(f"{', '.join(sorted(bad))} cannot be evaluated here (its "
                                      f"result depends on more than the cells it names)")
    return info


@functools.lru_cache(maxsize=1)
def _plain_functions() -> frozenset[str]:
    """formulas' functions whose node is one callable on its arguments (not, as ROW's, a node
    with more inputs than its arguments)."""
    return frozenset(k for k, v in get_functions().items() if _plain_function(v) is not None)


def _plain_function(entry):
    """The callable of a get_functions() entry whose node calls it on its arguments alone:
    the entry itself, or the 'function' of a dict that adds nothing but options schedula uses
    for scheduling (IF's solve_cycle); None otherwise."""
    if callable(entry):
        return entry
    if isinstance(entry, dict) and callable(entry.get("function")) \
            and set(entry) <= {"function", "solve_cycle", "wait_inputs"}:
        return entry["function"]
    return None


def _formulas_tokenize(formula: str) -> TokenInfo:
    try:
        tokens, builder = _parser().ast(formula)
    except Exception as ex:  # formulas raises several error types for bad syntax
        raise UnsupportedFormulaError(f"cannot parse {formula!r}: {ex!r}") from ex
    spans, keys, functions = [], [], set()
    for tok in tokens:
        if isinstance(tok, Range):
            if tok.attr.get("indirect") or tok.attr.get("anchor"):
                raise UnsupportedFormulaError("a reference made at run time (INDIRECT, OFFSET) "
                                              "cannot be evaluated here")
            text = tok.source[:tok.end_match]
            start = len(formula) - len(tok.source) + len(text) - len(text.lstrip())
            spans.append((start, start + len(text.strip())))
            keys.append(tok.attr["name"])
        elif isinstance(tok, Function):
            functions.add(tok.name.upper())
        elif isinstance(tok, Intersect):
            functions.add(" ")
        elif isinstance(tok, OperatorToken):
            functions.add(tok.name)
    return TokenInfo(spans, keys, functions, builder)


def _skeleton(formula: str, spans) -> str:
    """The formula with every reference replaced by a mark: formulas that differ only in which
    cells they read share a skeleton (and a compiled function)."""
    parts, pos = [], 0
    for start, end in spans:
        parts += [formula[pos:start], "\0"]
        pos = end
    parts.append(formula[pos:])
    return "".join(parts)


def _shape(formula, spans, refs: References, sheet, row, col) -> tuple[str, list[RefDesc]]:
    parts, descs, pos = [], [], 0
    for start, end in spans:
        desc = refs.ref(formula[start:end], sheet, row, col)
        parts += [formula[pos:start], desc.canonical()]
        descs.append(desc)
        pos = end
    parts.append(formula[pos:])
    return "".join(parts), descs


# --------------------------------------------------------------------------- compiled shapes

class _Batch:
    """Rows of the current vector call (1 outside vector calls); shared by a group's nodes.
    `row_by_row` counts node calls that had to run row by row, `numeric` those that ran on float
    arrays (NUMERIC_FORMS)."""
    n = 1
    row_by_row = 0
    numeric = 0


# formulas runs an element-wise function through np.vectorize, one Python call per element with
# an error scan of its arguments (~10 µs): on a 361 × 51 grid of long formulas that is most of the
# time.  Where every argument is a finite number, the functions below give, element for element,
# the same bits and type as formulas' own per-element call (its lambda on Python floats, or the
# numpy ufunc on a scalar); tests/test_engine.py checks that on random and edge values.  An element
# whose argument is not a finite number, or whose result is not finite (formulas turns it into
# #NUM!, #DIV/0!, #VALUE!), is left to formulas' own call.
def _typed(fn, kind):
    """An array function whose elements formulas gives as `kind` (its lambdas on Python floats
    give float, a numpy ufunc on a scalar gives np.float64)."""
    return lambda *xs: (fn(*xs), kind)


def _power(x, y):
    # Python's float ** (as in formulas' lambda), not np.power: libm pow and numpy's SIMD pow
    # differ in the last bit.  A complex or overflowing result becomes NaN: formulas decides it.
    out = np.empty(len(x))
    for i, (a, b) in enumerate(zip(x.tolist(), y.tolist())):
        try:
            v = a ** b
        except (OverflowError, ZeroDivisionError):
            v = np.nan
        out[i] = v if type(v) is float else np.nan
    return out, float


def _divide(x, y):
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(y == 0, np.nan, x / np.where(y == 0, 1.0, y)), float


def _atan2(x, y):
    return np.where((x == 0) & (y == 0), np.nan, np.arctan2(y, x)), np.float64


NUMERIC_FORMS = {
    "+": _typed(np.add, float), "-": _typed(np.subtract, float),
    "*": _typed(np.multiply, float), "u-": _typed(np.negative, float),
    "/": _divide, "^": _power, "ATAN2": _atan2,
    **{name: _typed(fn, np.float64) for name, fn in {
        "SIN": np.sin, "COS": np.cos, "TAN": np.tan, "ACOS": np.arccos, "ASIN": np.arcsin,
        "ATAN": np.arctan, "SQRT": np.sqrt, "RADIANS": np.radians, "DEGREES": np.degrees,
        "ABS": np.abs, "EXP": np.exp}.items()},
}
_NUMBER_TYPES = frozenset({float, int, np.float64, np.int64})


def _columns_of(args, n: int, types: frozenset):
    """The arguments of a node over n rows as object arrays of n (a scalar of `types`, or an
    array of one value, repeated); None when an argument is not such an array or scalar."""
    flat = []
    for a in args:
        if isinstance(a, np.ndarray) and a.size in (1, n):
            a = a.reshape(-1)
        elif type(a) in types:
            a = np.array([a], object)
        else:
            return None
        flat.append(np.broadcast_to(a, (n,)) if a.size == 1 else a)
    return flat


def _rows_of(args, n: int, types: frozenset):
    """The arguments of a node over n rows as (object arrays of n, the rows where every
    argument is of `types`, float arrays of n with those rows filled); None when an argument is
    not a plain array or scalar."""
    flat = _columns_of(args, n, types)
    if flat is None:
        return None
    plain = np.ones(n, bool)
    for a in flat:
        plain &= np.fromiter((type(v) in types for v in a), bool, n)
    xs = []
    for a in flat:
        x = np.zeros(n)
        x[plain] = a[plain].astype(float)
        xs.append(x)
    return flat, plain, xs


def _numeric_call(form, func, args, n: int):
    """`func` (formulas' node) over n rows: `form` on the rows where it applies, `func` on the
    rest.  None when an argument is not a plain array or scalar (the caller uses `func`)."""
    rows = _rows_of(args, n, _NUMBER_TYPES)
    if rows is None:
        return None
    flat, plain, xs = rows
    with np.errstate(all="ignore"):
        result, kind = form(*xs)
    plain &= np.isfinite(result)
    out = np.empty(n, object)
    out[:] = result.tolist() if kind is float else list(result)
    if not plain.all():
        rest = ~plain
        sub = func(*[a[rest].reshape(-1, 1) if a.size == n and not _is_broadcast(a) else
                     np.asarray(a[:1], object).reshape(1, 1) for a in flat])
        k = int(rest.sum())
        if not isinstance(sub, np.ndarray) or sub.size != k:    # an exception collapsed it
            return None
        out[rest] = sub.reshape(-1)
    return out.reshape(n, 1).view(Array)


# MIN, MAX and COUNT computed on arrays: in vector calls one result per row over that row's
# arguments (the cosine rule's domain test ABS(s-MAX(p,q))>MIN(p,q)), elsewhere one result over
# every value of the ranges they read (a summary's MIN of a 3,601-row sweep column).  formulas
# gives MIN (MAX) the first smallest (largest) number itself, as Python's min (max) does, and 0
# when there is none, and COUNT the number of numbers; what they skip in a range (empty cells,
# booleans, text that is not a number, and for COUNT errors) is skipped here too.  A row holding
# anything else (an error for MIN or MAX, text that reads as a number, a NaN or an infinity, an
# integer beyond 2^53, another type) is left to formulas' own call, as is a call with an
# argument of its own that is not a number (MAX(TRUE, ...)).
AGGREGATES = frozenset({"MIN", "MAX", "COUNT"})
_NUMBER, _INTEGER, _SKIPPED, _TEXT, _ERROR, _TOKEN, _OTHER = range(7)
_KIND_OF_TYPE = {float: _NUMBER, np.float64: _NUMBER, int: _INTEGER, np.int64: _INTEGER,
                 bool: _SKIPPED, np.bool_: _SKIPPED, str: _TEXT, XlError: _ERROR,
                 type(sh.EMPTY): _TOKEN}
_EXACT_INTEGER = 2.0 ** 53      # every integer up to it is a float exactly: comparisons agree


def _numbers_in(table: np.ndarray, skip_errors: bool):
    """Of an object array of values as ranges hold them: (where the numbers are, the numbers
    as floats with 0 elsewhere, where a value needs formulas' own judgement)."""
    flat = table.reshape(-1)
    kinds = np.fromiter(map(_KIND_OF_TYPE.get, map(type, flat), itertools.repeat(_OTHER)),
                        np.int8, flat.size)
    numbers = (kinds == _NUMBER) | (kinds == _INTEGER)
    x = np.zeros(flat.size)
    bad = kinds == _OTHER
    try:
        x[numbers] = flat[numbers].astype(float)
    except OverflowError:           # an integer beyond any float
        return numbers, x, np.ones(table.shape, bool)
    bad |= numbers & ~np.isfinite(x)
    bad |= (kinds == _INTEGER) & (np.abs(x) > _EXACT_INTEGER)
    if not skip_errors:
        bad |= kinds == _ERROR
    text = np.flatnonzero(kinds == _TEXT)
    numeric = {v for v in set(flat[text].tolist()) if is_number(v)}
    if numeric:
        bad[text] |= np.fromiter((v in numeric for v in flat[text]), bool, text.size)
    for i in np.flatnonzero(kinds == _TOKEN):
        bad[i] |= flat[i] is not sh.EMPTY
    return numbers.reshape(table.shape), x.reshape(table.shape), bad.reshape(table.shape)


def _aggregate_rows(name: str, table: np.ndarray):
    """MIN, MAX or COUNT of each row of an object table, as formulas computes it on rows that
    hold no value _numbers_in leaves to formulas; and the rows that hold one."""
    numbers, x, bad = _numbers_in(table, skip_errors=name == "COUNT")
    if name == "COUNT":
        return [int(k) for k in numbers.sum(axis=1)], bad.any(axis=1)
    if name == "MIN":
        winner = np.argmin(np.where(numbers, x, np.inf), axis=1)
    else:
        winner = np.argmax(np.where(numbers, x, -np.inf), axis=1)
    found = numbers.any(axis=1)
    return ([table[i, j] if f else 0 for i, (j, f) in enumerate(zip(winner.tolist(),
                                                                      found.tolist()))],
            bad.any(axis=1))


def _aggregate_call(name: str, func, args, n: int):
    """MIN, MAX or COUNT over n rows (one value per argument and row): on arrays where
    _aggregate_rows applies, `func` row by row on the rest.  None when an argument is not a
    plain array or number (the caller runs `func` row by row)."""
    columns = _columns_of(args, n, _NUMBER_TYPES)
    if columns is None or any(a.dtype != object for a in columns if isinstance(a, np.ndarray)):
        return None     # an array of numpy numbers: its values are not the objects it holds
    table = np.stack(columns, axis=1)
    values, bad = _aggregate_rows(name, table)
    out = np.empty(n, object)
    out[:] = values
    cols = [np.reshape(a, (n, 1)) if _size(a) == n else None for a in args]
    for i in np.flatnonzero(bad).tolist():
        out[i] = _single(func(*[a if c is None else c[i:i + 1] for a, c in zip(args, cols)]))
    return out.reshape(n, 1).view(Array)


def _ranges_node(func, name: str):
    """Wrap a MIN, MAX or COUNT node for calls outside vector calls: one result over every value
    of its arguments (the ranges' values in order, row by row), computed on arrays where
    _aggregate_rows applies to all of them, else by `func`."""
    def node(*args, **kw):
        if kw:
            return func(*args, **kw)
        try:
            values = parse_ranges(*args)[0]
        except Exception:       # formulas' own call decides (a range it cannot read)
            return func(*args)
        if not any(isinstance(a, np.ndarray) and a.size > 1 for a in values):
            return func(*args)
        parts = []
        for a in values:
            if isinstance(a, np.ndarray) and a.dtype == object:
                parts.append(a.reshape(-1))
            elif type(a) in _NUMBER_TYPES:
                parts.append(np.array([a], object))
            else:
                return func(*args)
        result, bad = _aggregate_rows(name, np.concatenate(parts).reshape(1, -1))
        return func(*args) if bad[0] else result[0]
    node.formulas_function = func       # what the node stands for (tests compare graphs by it)
    return node


def _is_broadcast(a: np.ndarray) -> bool:
    return a.strides == (0,)


def _size(x) -> int:
    return x.size if isinstance(x, np.ndarray) else 1


def _single(x):
    """The one value of a per-row result."""
    if isinstance(x, np.ndarray):
        if x.size != 1:
            raise _NotScalar
        return x.reshape(-1)[0]
    return x


class _NotScalar(Exception):
    """A row-by-row node returned more than one value: the group cannot be vectorized."""


def _vector_node(func, batch: _Batch, elementwise: bool, numeric=None, aggregate=None):
    """Wrap a node of the compiled graph for (n, 1) calls.  A node with a numeric form runs it
    on the rows of finite numbers, MIN, MAX and COUNT (`aggregate`, their name) on the rows of
    plain numbers (AGGREGATES).  Element-wise nodes run once; if their output is not (n, 1) (an exception collapsed
    it), or the node is not element-wise, it runs row by row on (1, 1) slices, exactly as in a
    per-cell call."""
    def node(*args, **kw):
        n = batch.n
        if n == 1 or not any(_size(a) == n for a in args):
            return func(*args, **kw)
        if numeric is not None and not kw:
            out = _numeric_call(numeric, func, args, n)
            if out is not None:
                batch.numeric += 1
                return out
        if aggregate is not None and not kw:
            out = _aggregate_call(aggregate, func, args, n)
            if out is not None:
                batch.numeric += 1
                return out
        if elementwise:
            out = func(*args, **kw)
            if isinstance(out, np.ndarray) and out.shape == (n, 1):
                return out
        batch.row_by_row += 1
        out = np.empty((n, 1), object)
        cols = [np.reshape(a, (n, 1)) if _size(a) == n else None for a in args]
        for i in range(n):
            row = [a if c is None else c[i:i + 1] for a, c in zip(args, cols)]
            out[i, 0] = _single(func(*row, **kw))
        return out.view(Array)
    return node


def _compile(graph, batch: _Batch | None = None, host: Ranges | None = None):
    """Compile a parsed formula (a grammar.Parsed or a `formulas` AstBuilder); with `batch`,
    every node is wrapped for vector calls."""
    extra = {_cell_token(): host} if host is not None else {}
    if isinstance(graph, grammar.Parsed):
        pipe = _Pipe.of_parsed(graph, batch, extra)
        if pipe is not None:
            return pipe
        graph = _parser().ast(graph.formula)[1]
    _wrap_nodes(graph, batch)
    return _Pipe.of(graph, extra) or graph.compile(**extra)


def _wrap_nodes(builder, batch: _Batch | None) -> None:
    for node_id, node in builder.dsp.function_nodes.items():
        node["function"] = _wrap(node["function"], re.sub(r"<\d+>$", "", node_id), batch)


def _wrap(func, name: str, batch: _Batch | None):
    """A node's function as the graph runs it: for vector calls, wrapped by its name; outside
    them, MIN, MAX and COUNT wrapped to read their ranges on arrays."""
    if batch is None:
        return _ranges_node(func, name) if name in AGGREGATES else func
    return _vector_node(func, batch, name in ELEMENTWISE, NUMERIC_FORMS.get(name),
                        name if name in AGGREGATES else None)


def _formulas_graph(formula: str, batch: _Batch | None, extra: dict):
    """The graph `formulas` compiles for a formula (a pipe's fallback)."""
    builder = _parser().ast(formula)[1]
    _wrap_nodes(builder, batch)
    return builder.compile(**extra)


def _input_templates(keys) -> dict:
    """compile()'s inputs for the references and names a formula reads: each key, in sorted
    order, with its range (None for a defined name)."""
    inputs = {}
    for k in sorted(keys):
        try:
            inputs[k] = Ranges().push(k)
        except AnchorRangeName:
            inputs[k] = sh.NONE
        except InvalidRangeName:
            inputs[k] = None
    return inputs


class _Pipe:
    """A parsed formula's function nodes called one after the other in dependency order: the
    same functions on the same arguments as the graph `formulas` compiles, without building
    schedula's dispatcher (most of the cost of compiling) or running its dispatch (about 1 ms a
    call).  `inputs` are the ones `compile()` gives: every reference and name the formula reads,
    in sorted order, with its range.  A constant part is computed at each call, not once.  A
    node that gives no value sends the call to the compiled graph."""

    def __init__(self, graph, inputs, steps, defaults, output):
        self.graph, self.compiled = graph, None     # graph(): the compiled graph, on demand
        self.inputs = inputs
        self.steps = steps
        self.defaults = defaults
        self.output = output

    @classmethod
    def of(cls, builder, extra: dict) -> "_Pipe | None":
        """The pipe of builder's graph, or None where it takes more than a plain order: a node
        with several outputs or options, a function that behaves otherwise while compiling, an
        operator on references."""
        dsp = builder.dsp
        output = builder.get_node_id(builder[-1])
        functions, producer = {}, {}
        for fid, node in dsp.function_nodes.items():
            if len(node["outputs"]) != 1 or set(node) - _PLAIN_FUNCTION_KEYS \
                    or COMPILING in node["inputs"] \
                    or re.sub(r"<\d+>$", "", fid) in _REFERENCE_OPERATORS:
                return None
            functions[fid] = node
            producer[node["outputs"][0]] = fid
        defaults = {k: v["value"] for k, v in dsp.default_values.items()} | extra
        defaults[sh.START] = sh.NONE      # the input of a function without arguments, PI()
        if output not in producer or any(
                d.get("filters") for k, d in dsp.data_nodes.items() if k != output):
            return None
        inputs = _input_templates(k for k in dsp.data_nodes
                                  if k not in producer and k not in defaults and k is not sh.START)
        order = graphlib.TopologicalSorter(
            {fid: {producer[i] for i in n["inputs"] if i in producer}
             for fid, n in functions.items()}).static_order()
        steps = [(functions[f]["function"], tuple(functions[f]["inputs"]),
                  functions[f]["outputs"][0]) for f in order]
        return cls(lambda: builder.compile(**extra), inputs, steps, defaults, output)

    @classmethod
    def of_parsed(cls, parsed: grammar.Parsed, batch: _Batch | None,
                  extra: dict) -> "_Pipe | None":
        """The pipe of grammar's graph: its nodes in their order (each after its arguments),
        with the functions `formulas`' tokens compile to.  None if the result is not a call."""
        if parsed.nodes[-1][0] != "call":
            return None         # a lone reference or constant: compile() and its filter
        table, ids, keys, steps = get_functions(), [], [], []
        defaults = dict(extra)
        for i, node in enumerate(parsed.nodes):
            if node[0] == "input":
                ids.append(node[1])
                keys.append(node[1])
            elif node[0] == "const":
                ids.append(i)
                defaults[i] = node[1]
            else:
                _, name, args = node
                func = OPERATORS[name.upper()] if name in grammar.OPERATORS \
                    else _plain_function(table[name.upper()])
                steps.append((_wrap(func, name, batch), tuple(ids[a] for a in args), i))
                ids.append(i)
        formula = parsed.formula
        return cls(lambda: _formulas_graph(formula, batch, extra), _input_templates(keys),
                   steps, defaults, len(parsed.nodes) - 1)

    def __call__(self, *args):
        values = dict(self.defaults)
        values.update(zip(self.inputs, args))
        for func, inputs, output in self.steps:
            value = func(*[v for i in inputs if (v := values[i]) is not sh.NONE])  # as schedula
            if value is sh.NONE:    # no value (formulas' RangeValueError): schedula decides
                if self.compiled is None:
                    self.compiled = self.graph()
                return self.compiled(*args)
            values[output] = value
        # compile()'s filter on the result: a range becomes its values
        return parse_ranges(values[self.output])[0][0]


# Union, intersection and range operators: compile() resolves them to one input range.
_REFERENCE_OPERATORS = frozenset({",", " ", ":"})
_PLAIN_FUNCTION_KEYS = frozenset({"type", "function", "inputs", "outputs", "wait_inputs",
                                  "index", "solve_cycle"})


def _call(func, args):
    """Call a compiled formula as ExcelModel does (#NAME? for unimplemented functions)."""
    try:
        return func(*args)
    except NotImplementedError:
        return Error.errors["#NAME?"]
    except sh.DispatcherError as ex:
        if isinstance(getattr(ex, "ex", None), NotImplementedError):
            return Error.errors["#NAME?"]
        raise


_ONE_CELL = Ranges.get_range("A1")


def _replace_empty(out: np.ndarray) -> np.ndarray:
    """replace_empty (EMPTY -> 0), skipping its element-wise == scan when nothing is EMPTY."""
    if any(v is sh.EMPTY for v in out.reshape(-1)):
        return np.asarray(replace_empty(out), dtype=object)
    return out


def _cell_result(out):
    """A compiled formula's output as ExcelModel stores it for one cell."""
    return Ranges().set_value(dict(_ONE_CELL), replace_empty(out)).value[0, 0]


# --------------------------------------------------------------------------- groups

@dataclass
class _Member:
    row: int
    col: int
    formula: str


@dataclass
class _EachCell:
    """A member compiled on its own ('each' mode)."""
    func: object
    inputs: list  # per compiled input: ('ranges', Ranges template, rects) or ('name', RefDesc)
    rects: list


@dataclass
class Group:
    gid: int
    sheet: str
    shape: str
    members: list[_Member]
    info: TokenInfo            # of members[0]
    descs: list[RefDesc]       # per reference of the shape: the same for every member
    mode: str = "vector"
    func: object = None
    inputs: list[RefDesc] = field(default_factory=list)   # per compiled input, in order
    batch: _Batch = field(default_factory=_Batch)
    each: list[_EachCell] = field(default_factory=list)
    rows: np.ndarray = None
    cols: np.ndarray = None

    def reads(self, i: int) -> list[tuple[str, int, int, int, int]]:
        """Rectangles (sheet, top, left, bottom, right) read by member i."""
        if self.mode == "each":
            return self.each[i].rects
        m = self.members[i]
        return [d.rect(m.row, m.col) for d in self.inputs]


class Engine:
    """One evaluation of one workbook; `stats` tells how it was grouped and run."""

    def __init__(self, wb, vectorize: bool = True, only=None,
                 excel_model_constants: bool = False):
        self.wb = wb
        self.excel_model_constants = excel_model_constants
        self.only = only
        self.vectorize = vectorize
        self.refs = References.of(wb)
        self.constants: dict[str, dict[tuple[int, int], object]] = {}
        self.groups: list[Group] = []
        self.grid: dict[str, np.ndarray] = {}
        self.owner: dict[str, np.ndarray] = {}
        self.member: dict[str, np.ndarray] = {}
        self.stats = dict(formula_cells=0, shapes=0, compiled=0, reused=0, vector_groups=0,
                          cell_groups=0, each_groups=0, cyclic_cells=0, tokenized_cells=0,
                          vector_fallbacks=0, row_by_row_nodes=0, split_groups=0)

    # ---- pipeline
    def run(self) -> dict[tuple[str, str], object]:
        self._prepare()
        # Overflow warnings would only repeat what the #NUM!/#VALUE! results say; 'ignore' and
        # numpy's default 'warn' give the same values.
        with np.errstate(all="ignore"):
            for component in self.order:
                self._evaluate_component(component)
        batches = {id(g.batch): g.batch for g in self.groups}.values()   # groups share them
        self.stats["row_by_row_nodes"] = sum(b.row_by_row for b in batches)
        self.stats["numeric_nodes"] = sum(b.numeric for b in batches)
        return self._values()

    def _prepare(self) -> None:
        """Group, plan, allocate and order: everything but the evaluation."""
        if self.groups or self.constants:
            raise EngineError("an Engine runs once; make a new one")
        if self.only is None:
            self._group(self._read_cells(self.wb.worksheets))
        else:
            self._group_needed(self.only)
        for g in self.groups:
            self._plan(g)
        self._allocate()
        self.order = self._untangled_components()

    # ---- 1. cells
    def _read_cells(self, worksheets) -> dict[str, list[tuple[int, int, str]]]:
        """The formulas of `worksheets` by sheet, sorted by row and column; their constants go
        to self.constants."""
        formulas_by_sheet = {}
        for ws in worksheets:
            consts, forms = {}, []
            for (row, col), cell in ws._cells.items():  # only cells that exist (ExcelModel too)
                if cell.value is None:
                    continue
                if cell.data_type == "f":
                    forms.append((row, col, _formula_text(cell)))
                else:
                    value = _constant(cell, self.excel_model_constants)
                    if value is not None:
                        consts[(row, col)] = value
            forms.sort()
            self.constants[ws.title] = consts
            formulas_by_sheet[ws.title] = forms
            self.stats["formula_cells"] += len(forms)
        return formulas_by_sheet

    # ---- 2. shapes
    def _group(self, formulas_by_sheet):
        candidates: dict[tuple[str, str], list[_Member]] = {}
        for sheet, forms in formulas_by_sheet.items():
            above, left = {}, {}   # last (row, col, shape, template) per column / per row
            for row, col, formula in forms:
                copied = self._copied_shape(formula, row, col, above, left)
                if copied is not None:
                    above[col] = left[row] = copied
                    shape = copied[2]
                else:
                    try:
                        shape, template = self.refs.fast_shape(formula, sheet, row, col)
                        above[col] = left[row] = (row, col, shape, template)
                    except UnsupportedFormulaError:
                        shape = "\0" + formula   # the tokenizer decides below
                candidates.setdefault((sheet, shape), []).append(_Member(row, col, formula))
        exact: dict[tuple[str, str], tuple[list[_Member], TokenInfo, list[RefDesc]]] = {}
        for (sheet, shape), members in candidates.items():
            rep = members[0]
            lexed = None if shape.startswith("\0") else _lex_spans(rep.formula, self.refs)
            skeleton = None if lexed is None else _skeleton(rep.formula, lexed)
            read = _READ_SKELETONS.get(skeleton)
            info = (TokenInfo(lexed, None, read, None) if read is not None
                    else self._tokenize(rep, sheet))
            if lexed is not None and info.spans == lexed:
                exact_shape, descs = self._exact_shape(rep, sheet, info)
                if exact_shape == shape:
                    _READ_SKELETONS[skeleton] = info.functions
                    exact[(sheet, shape)] = (members, info, descs)
                    continue
            if info.builder is None:
                info = self._tokenize(rep, sheet)
            for m in members:  # the lexer misread this shape: re-read every member exactly
                m_info = info if m is rep else self._tokenize(m, sheet)
                exact_shape, descs = self._exact_shape(m, sheet, m_info)
                entry = exact.setdefault((sheet, "\0" + exact_shape), ([], m_info, descs))
                entry[0].append(m)
        for (sheet, shape), (members, info, descs) in exact.items():
            self.groups.append(Group(len(self.groups), sheet, shape, members, info, descs))
        self.stats["shapes"] = len(self.groups)

    def _group_needed(self, cells) -> None:
        """Group only what the formula cells among `cells` need, directly or not, following
        the references of each shape (before any compile: that is the cost saved).  A sheet is
        read and grouped when a needed group first reads it: a sheet that nothing needed reads
        (the Motion sheet, for the sweep's angles) is never read at all."""
        sheets = {ws.title: ws for ws in self.wb.worksheets}
        grouped: set[str] = set()
        needed: set[int] = set()
        todo_sheets = {sheet for sheet, _ in cells} & set(sheets)
        while todo_sheets:
            self._group(self._read_cells([sheets[s] for s in sorted(todo_sheets)]))
            grouped |= todo_sheets
            needed, read_sheets = self._needed_groups(cells)
            todo_sheets = (read_sheets & set(sheets)) - grouped
        self.groups = [g for g in self.groups if g.gid in needed]
        for gid, g in enumerate(self.groups):
            g.gid = gid

    def _needed_groups(self, cells) -> tuple[set[int], set[str]]:
        """The groups that the formula cells among `cells` need, and every sheet they read."""
        owner = {}
        for g in self.groups:
            rows, cols = owner.get(g.sheet, (0, 0))
            owner[g.sheet] = (max(rows, max(m.row for m in g.members)),
                              max(cols, max(m.col for m in g.members)))
        owner = {sheet: np.full((r + 1, c + 1), -1, dtype=np.int64)
                 for sheet, (r, c) in owner.items()}
        for g in self.groups:
            owner[g.sheet][[m.row for m in g.members], [m.col for m in g.members]] = g.gid
        todo = set()
        for sheet, a1 in cells:
            row, col = coordinate_to_tuple(a1)
            grid = owner.get(sheet)
            if grid is not None and row < grid.shape[0] and col < grid.shape[1]:
                todo.add(int(grid[row, col]))
        todo.discard(-1)
        needed, sheets = set(), set()
        while todo:
            gid = todo.pop()
            needed.add(gid)
            sheets.update(d.sheet for d in self.groups[gid].descs)
            todo |= self._owners_read(self.groups[gid], owner) - needed - {-1}
        return needed, sheets

    @staticmethod
    def _owners_read(g: Group, owner: dict[str, np.ndarray]) -> set[int]:
        """The groups (in `owner`, one grid per sheet) owning a cell that group g's references
        name, for any member."""
        rows = np.array([m.row for m in g.members])
        cols = np.array([m.col for m in g.members])
        found = set()
        for d in g.descs:
            grid = owner.get(d.sheet)
            if grid is None:
                continue
            r1, c1, r2, c2 = np.broadcast_arrays(*d.at(rows, cols), rows)[:4]
            if not d.is_range:      # one cell per member: one look-up for all of them
                inside = (r1 < grid.shape[0]) & (c1 < grid.shape[1])
                found.update(grid[r1[inside], c1[inside]].ravel().tolist())
                continue
            for a, b, c, e in {(int(a), int(b), int(c), int(e))
                               for a, b, c, e in zip(r1, c1, r2, c2)}:
                found.update(grid[a:c + 1, b:e + 1].ravel().tolist())
        return found

    @staticmethod
    def _copied_shape(formula, row, col, above, left):
        """The shape of the cell above (or to the left) if this formula is its copy; a copy has
        the same shape by definition, and checking it is much cheaper than lexing.  The entries
        keep the cell the template was made from, so every copy is a shift of that one."""
        for prev in (above.get(col), left.get(row)):
            if prev is None:
                continue
            prow, pcol, shape, template = prev
            if template.shifted(row - prow, col - pcol) == formula:
                return prev
        return None

    def _tokenize(self, member: _Member, sheet: str) -> TokenInfo:
        self.stats["tokenized_cells"] += 1
        try:
            return _tokenize(member.formula)
        except UnsupportedFormulaError as ex:
            raise UnsupportedFormulaError(f"{sheet}!{_a1(member.row, member.col)}: {ex}") from ex

    def _exact_shape(self, m: _Member, sheet: str, info: TokenInfo):
        try:
            return _shape(m.formula, info.spans, self.refs, sheet, m.row, m.col)
        except UnsupportedFormulaError as ex:
            raise UnsupportedFormulaError(f"{sheet}!{_a1(m.row, m.col)}: {ex}") from ex

    # ---- 3. compile
    def _plan(self, g: Group):
        g.rows = np.array([m.row for m in g.members], dtype=np.int64)
        g.cols = np.array([m.col for m in g.members], dtype=np.int64)
        functions = g.info.functions
        if functions & HOST_AWARE:
            return self._plan_each(g)
        rep = self._representative(g)
        if rep is None:
            return self._plan_each(g)
        vector = (self.vectorize and len(g.members) > 1 and functions <= VECTOR_SAFE
                  and not any(d.is_range for d in g.descs))
        g.mode = "vector" if vector else "cell"
        compiled = self._compiled(g, *rep)
        if compiled is None:
            return self._plan_each(g)   # unions, intersections: not tied to one reference
        g.func, positions = compiled
        g.inputs = [g.descs[i] for i in positions]
        self.stats[f"{g.mode}_groups"] += 1

    def _compiled(self, g: Group, rep: _Member, spans, keys):
        """(compiled function, index of the reference behind each of its inputs), or None when
        an input is not one reference.  Reused across groups and evaluations in this process:
        the function depends only on the text around the references, the pattern of equal
        references, the sheet and the mode (compiling is most of the cost of a small book)."""
        pattern = tuple(keys.index(k) for k in keys)
        skeleton = rep.formula if g.shape.startswith("\0") else _skeleton(rep.formula, spans)
        key = (g.sheet, skeleton, pattern, g.mode)
        cached = _COMPILED.get(key)
        if cached is not None:
            func, positions, g.batch = cached
            g.batch.row_by_row = g.batch.numeric = 0
            self.stats["reused"] += 1
            return func, positions
        info = g.info
        if rep is not g.members[0] or info.builder is None or info.keys is None:
            info = self._tokenize(rep, g.sheet)
        g.info = TokenInfo(info.spans, info.keys, info.functions, None)  # compile() consumes it
        func = _compile(info.builder, g.batch if g.mode == "vector" else None)
        self.stats["compiled"] += 1
        positions = []
        for name, template in func.inputs.items():
            i = info.keys.index(name) if name in info.keys else -1
            if i < 0 or not _same_cells(g.descs[i], template, rep, g.sheet, self.refs):
                return None
            positions.append(i)
        if tuple(info.keys.index(k) for k in info.keys) != pattern:
            return func, positions   # the tokenizer pairs references otherwise: not reusable
        if len(_COMPILED) >= _COMPILED_MAX:
            _COMPILED.pop(next(iter(_COMPILED)))
        _COMPILED[key] = (func, positions, g.batch)
        return func, positions

    def _representative(self, g: Group):
        """(member, spans, reference keys) of a member whose formula gives every compiled input
        one descriptor.  In row 5, `=B5+$B$5` has one input 'B5' for two descriptors; row 6 has
        two inputs, and its compiled function serves rows 5.. as well (two inputs that happen to
        hold one cell are still right).  None if no member fits."""
        n = len(g.members)
        for i in dict.fromkeys((0, min(1, n - 1), n // 2, n - 1)):
            m = g.members[i]
            if g.shape.startswith("\0"):    # the lexer misread this shape: the tokenizer's keys
                info = g.info if i == 0 else self._tokenize(m, g.sheet)
                spans, keys = info.spans, info.keys
            else:
                spans = g.info.spans if i == 0 else _lex_spans(m.formula, self.refs)
                keys = [m.formula[a:b].replace("$", "").upper() for a, b in spans]
            by_key, clash = {}, []
            for key, desc in zip(keys, g.descs):
                if by_key.setdefault(key, desc) != desc:
                    clash.append((by_key[key], desc))
            if not clash or all(self._always_same(g, a, b) for a, b in clash):
                return m, spans, keys
        return None

    @staticmethod
    def _always_same(g: Group, a: RefDesc, b: RefDesc) -> bool:
        """Do two descriptors name the same cells for every member (e.g. B8 and $B8 in C)?"""
        if a.sheet != b.sheet or a.is_range != b.is_range:
            return False
        shape = g.rows.shape
        return all(np.array_equal(np.broadcast_to(x, shape), np.broadcast_to(y, shape))
                   for x, y in zip(a.at(g.rows, g.cols), b.at(g.rows, g.cols)))

    def _plan_each(self, g: Group):
        g.mode, g.each = "each", []
        for m in g.members:
            info = self._tokenize(m, g.sheet)   # a fresh parse: compile() may have run on g.info
            host = Ranges().push(f"{_sheet_prefix(g.sheet)}{_a1(m.row, m.col)}")
            func = _compile(info.builder, host=host)
            self.stats["compiled"] += 1
            inputs, rects = [], []
            for key, template in func.inputs.items():
                if isinstance(template, Ranges):
                    cells = [self._range_rect(r, g.sheet) for r in template.ranges]
                    inputs.append(("ranges", template, cells))
                    rects += cells
                elif template is None and self.refs.is_name(key):
                    desc = self.refs.name(key)
                    inputs.append(("name", desc))
                    rects.append(desc.rect(m.row, m.col))
                else:
                    raise UnsupportedFormulaError(
                        f"{g.sheet}!{_a1(m.row, m.col)}: unknown reference {key!r}")
            g.each.append(_EachCell(func, inputs, rects))
        self.stats["each_groups"] += 1

    def _range_rect(self, r: dict, host_sheet: str):
        r1, r2, c1, c2 = int(r["r1"]), int(r["r2"]), r["n1"], r["n2"]
        if not (1 <= r1 <= r2 < MAX_ROW and 1 <= c1 <= c2 < MAX_COL):
            raise UnsupportedFormulaError(f"the whole-row/column or invalid range {r['name']!r} "
                                          "cannot be evaluated here")
        sid = r.get("sheet_id") or ""
        if sid.startswith("'"):
            sid = sid[1:-1].replace("''", "'")
        if "[" in sid:
            raise UnsupportedFormulaError(f"external reference {r['name']!r}")
        return (self.refs.sheet(sid) if sid else host_sheet), r1, c1, r2, c2

    # ---- 4. storage
    def _allocate(self):
        """Value grid (object, EMPTY where nothing), and which group/member owns each cell."""
        size = {ws.title: [ws.max_row, ws.max_column] for ws in self.wb.worksheets
                if ws.title in self.constants}          # the sheets read (all, without `only`)
        for g in self.groups:
            self._grow(size, g.sheet, int(g.rows.max()), int(g.cols.max()))
            if g.mode == "each":
                for cell in g.each:
                    for sheet, _, _, r2, c2 in cell.rects:
                        self._grow(size, sheet, r2, c2)
                continue
            for d in g.inputs:
                r1, c1, r2, c2 = d.at(g.rows, g.cols)
                self._grow(size, d.sheet, int(np.max(np.maximum(r1, r2))),
                           int(np.max(np.maximum(c1, c2))))
        for sheet, (rows, cols) in size.items():
            grid = np.empty((rows + 1, cols + 1), object)
            grid.fill(sh.EMPTY)
            for (r, c), v in self.constants.get(sheet, {}).items():
                grid[r, c] = v
            self.grid[sheet] = grid
            self.owner[sheet] = np.full((rows + 1, cols + 1), -1, dtype=np.int64)
            self.member[sheet] = np.full((rows + 1, cols + 1), -1, dtype=np.int64)
        for g in self.groups:
            self.owner[g.sheet][g.rows, g.cols] = g.gid
            self.member[g.sheet][g.rows, g.cols] = np.arange(len(g.members))

    @staticmethod
    def _grow(size, sheet, rows, cols):
        size[sheet][0] = max(size[sheet][0], rows)
        size[sheet][1] = max(size[sheet][1], cols)

    # ---- 5. order
    def _group_deps(self, g: Group) -> set[int]:
        deps = self._found_in(g, self.owner)
        deps.discard(-1)
        return deps

    def _found_in(self, g: Group, grids: dict[str, np.ndarray]) -> set[int]:
        """The values of `grids` (one per sheet, shaped like the value grid) over every cell
        that group g reads."""
        found = set()
        if g.mode == "each":
            for i in range(len(g.members)):
                for sheet, r1, c1, r2, c2 in g.reads(i):
                    found.update(grids[sheet][r1:r2 + 1, c1:c2 + 1].ravel().tolist())
        else:
            for d in g.inputs:
                grid = grids[d.sheet]
                if not d.is_range:
                    r1, c1, _, _ = d.at(g.rows, g.cols)
                    found.update(grid[r1, c1].ravel().tolist())
                    continue
                hosts = [(g.rows[0], g.cols[0])] if d.is_absolute else zip(g.rows, g.cols)
                for row, col in hosts:
                    _, r1, c1, r2, c2 = d.rect(int(row), int(col))
                    found.update(grid[r1:r2 + 1, c1:c2 + 1].ravel().tolist())
        return found

    def vary(self, sheet: str, cell: str, inputs, read) -> Iterator[dict]:
        """For each value of `inputs` put into the constant cell (sheet, cell), the values of
        the cells `read` ((sheet, 'B7') each; None for a cell outside every sheet).

        Only what the read cells need is evaluated: once what does not move with the input,
        then what does, once for all the input values together: the input values are one more
        batch dimension of the compiled vector functions (a group that cannot take it is
        evaluated value by value, cell by cell). Groups count whole, so a little more than
        needed may be evaluated, never less."""
        self._prepare()
        read = list(read)
        row, col = coordinate_to_tuple(cell)
        grid = self.grid.get(sheet)
        if grid is None or row >= grid.shape[0] or col >= grid.shape[1]:
            raise EngineError(f"no cell {sheet}!{cell}")
        if self.owner[sheet][row, col] >= 0:
            raise EngineError(f"{sheet}!{cell} holds a formula, not an input value")
        targets = []
        for s, a1 in read:
            r, c = coordinate_to_tuple(a1)
            if s in self.grid and r < self.grid[s].shape[0] and c < self.grid[s].shape[1]:
                targets.append((s, a1, r, c))
        deps = {g.gid: self._group_deps(g) for g in self.groups}
        needed = _closure({int(self.owner[s][r, c]) for s, _, r, c in targets} - {-1}, deps)
        with np.errstate(all="ignore"):
            for component in self.order:          # what the read cells need, once
                if needed.intersection(component):
                    self._evaluate_component(component)
        inputs = list(inputs)
        varying = {(sheet, row, col): np.array(inputs, dtype=object)}
        readers: dict[int, set[int]] = {}
        for gid, ds in deps.items():
            for d in ds:
                readers.setdefault(d, set()).add(gid)
        marks = {s: np.zeros(g.shape, dtype=np.int8) for s, g in self.grid.items()}
        marks[sheet][row, col] = 1
        first = {gid for gid in needed if 1 in self._found_in(self.groups[gid], marks)}
        reached = _closure(first, readers) & needed
        with np.errstate(all="ignore"):
            for component in self.order:          # then what moves with the input, per value
                if not reached.intersection(component):
                    continue
                if len(component) == 1 and component[0] not in self.self_reading \
                        and self._vary_vector(self.groups[component[0]], varying, len(inputs)):
                    continue
                self._vary_cells(component, varying, len(inputs))
        for f in range(len(inputs)):
            out = dict.fromkeys(read)
            for s, a1, r, c in targets:
                value = varying[(s, r, c)][f] if (s, r, c) in varying else self.grid[s][r, c]
                out[(s, a1)] = _public_value(value, self.owner[s][r, c] >= 0)
            yield out

    def _vary_vector(self, g: Group, varying: dict, n: int) -> bool:
        """One call of g's vector function for all members × all input values; False (nothing
        stored) where g has no vector form or the result is not one value per row."""
        if g.mode not in ("vector", "cell") or not g.info.functions <= VECTOR_SAFE \
                or any(d.is_range for d in g.inputs):
            return False
        func, batch, inputs = ((g.func, g.batch, g.inputs) if g.mode == "vector"
                               else self._vector_form(g))
        if func is None:
            return False
        m = len(g.members)
        args = []
        for d in inputs:
            r1, c1, _, _ = d.at(g.rows, g.cols)
            rows, cols = np.broadcast_arrays(r1, c1, g.rows)[:2]
            column = np.empty((m, n), dtype=object)
            for i, (r, c) in enumerate(zip(rows.tolist(), cols.tolist())):
                column[i, :] = varying.get((d.sheet, r, c), self.grid[d.sheet][r, c])
            args.append(column.reshape(m * n, 1))
        values = _per_row(func, batch, args, m * n, bool(inputs))
        if values is None:
            return False
        for i, member in enumerate(g.members):
            varying[(g.sheet, member.row, member.col)] = values[i * n:(i + 1) * n]
        return True

    def _vector_form(self, g: Group):
        """(vector-compiled function, its batch, the reference behind each of its inputs) of a
        group planned cell by cell; (None, None, None) where it has none."""
        rep = self._representative(g)
        if rep is None:
            return None, None, None
        mode, batch, info = g.mode, g.batch, g.info
        g.mode, g.batch = "vector", _Batch()
        try:
            compiled = self._compiled(g, *rep)
            if compiled is None:
                return None, None, None
            func, positions = compiled
            return func, g.batch, [g.descs[i] for i in positions]  # the batch may be a cached one
        finally:
            g.mode, g.batch, g.info = mode, batch, info

    def _vary_cells(self, component: list[int], varying: dict, n: int) -> None:
        """The fallback: the component evaluated cell by cell, once per input value."""
        cells = [(self.groups[gid].sheet, m.row, m.col)
                 for gid in component for m in self.groups[gid].members]
        results = {key: np.empty(n, dtype=object) for key in cells}
        for f in range(n):
            for (s, r, c), values in varying.items():
                self.grid[s][r, c] = values[f]
            self._evaluate_component(component)
            for key in cells:
                results[key][f] = self.grid[key[0]][key[1], key[2]]
        varying.update(results)

    def _components(self) -> list[list[int]]:
        """Strongly connected components of the group graph, dependencies first (Tarjan)."""
        deps = [sorted(self._group_deps(g)) for g in self.groups]
        self.self_reading = {g.gid for g in self.groups if g.gid in deps[g.gid]}
        index, low, on_stack, stack, out, counter = {}, {}, set(), [], [], [0]
        for root in range(len(self.groups)):
            if root in index:
                continue
            work = [(root, 0)]
            while work:
                v, i = work.pop()
                if i == 0:
                    index[v] = low[v] = counter[0]
                    counter[0] += 1
                    stack.append(v)
                    on_stack.add(v)
                if i < len(deps[v]):
                    work.append((v, i + 1))
                    w = deps[v][i]
                    if w not in index:
                        work.append((w, 0))
                    elif w in on_stack:
                        low[v] = min(low[v], index[w])
                    continue
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    out.append(component)
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[v])
        return out

    def _untangled_components(self) -> list[list[int]]:
        """Components after splitting the groups that tie several groups into one cycle.

        A group joins cells by shape, not by position, so two groups can read each other
        without any cell reading itself: `=SQRT(E5^2+F5^2)` in columns G and M of a sweep is one
        group, and if M reads a column that reads G, the two groups are one cycle.  Evaluated
        cell by cell, such a cycle costs a compiled call per cell.  So a group of a cycle that
        spans several columns is split into one group per column; where no such group is left,
        the smallest groups are split into single cells; and again, until every cycle left is
        real (a column that reads itself, or a circular reference).  A sweep column stays
        whole."""
        while True:
            components = self._components()
            victims = []
            for component in components:
                if len(component) < 2:
                    continue
                groups = [self.groups[gid] for gid in component]
                wide = [g for g in groups if len(set(g.cols.tolist())) > 1]
                if wide:
                    victims += [(g, lambda m: m.col) for g in wide]
                    continue
                splittable = [len(g.members) for g in groups if len(g.members) > 1]
                victims += [(g, lambda m: (m.row, m.col)) for g in groups
                            if splittable and len(g.members) == min(splittable)]
            if not victims:
                return components
            for g, key in victims:
                self._split(g, key)
            self.stats["split_groups"] += len(victims)

    def _split(self, g: Group, key) -> None:
        """One group per value of key(member); the first keeps the gid, all share the compiled
        function and its inputs."""
        parts: dict[object, list[int]] = {}
        for i, m in enumerate(g.members):
            parts.setdefault(key(m), []).append(i)
        index = list(parts.values())
        for idx in index[1:]:
            part = Group(len(self.groups), g.sheet, g.shape, [g.members[i] for i in idx],
                         g.info, g.descs, g.mode, g.func, g.inputs, g.batch,
                         [g.each[i] for i in idx] if g.each else [], g.rows[idx], g.cols[idx])
            self.groups.append(part)
            self.owner[g.sheet][part.rows, part.cols] = part.gid
            self.member[g.sheet][part.rows, part.cols] = np.arange(len(idx))
        first = index[0]
        g.members = [g.members[i] for i in first]
        g.each = [g.each[i] for i in first] if g.each else []
        g.rows, g.cols = g.rows[first], g.cols[first]

    # ---- 6. evaluation
    def _evaluate_component(self, component: list[int]):
        if len(component) == 1 and component[0] not in self.self_reading:
            g = self.groups[component[0]]
            if g.mode == "vector" and self._evaluate_vector(g):
                return
            for i in range(len(g.members)):
                self._evaluate_cell(g, i)
            return
        for gid, i in self.cell_order(set(component)):
            self._evaluate_cell(self.groups[gid], i)

    def _evaluate_vector(self, g: Group) -> bool:
        """One call for the whole group; False (nothing stored) if the result is not per row."""
        n = len(g.members)
        args = []
        for d in g.inputs:
            r1, c1, _, _ = d.at(g.rows, g.cols)
            rows, cols = np.broadcast_arrays(r1, c1, g.rows)[:2]  # absolute refs: one cell, n times
            args.append(self.grid[d.sheet][rows, cols].reshape(n, 1))
        values = _per_row(g.func, g.batch, args, n, bool(g.inputs))
        if values is None:
            self.stats["vector_fallbacks"] += 1
            return False
        self.grid[g.sheet][g.rows, g.cols] = values
        return True

    def _evaluate_cell(self, g: Group, i: int):
        m = g.members[i]
        if g.mode == "each":
            cell = g.each[i]
            func = cell.func
            args = [self._name_arg(x[1], m) if x[0] == "name" else self._ranges_arg(x[1], x[2])
                    for x in cell.inputs]
        else:
            func = g.func
            args = [self._desc_arg(d, m) for d in g.inputs]
        try:
            value = _cell_result(_call(func, args))
        except Exception as ex:
            raise EngineError(f"{g.sheet}!{_a1(m.row, m.col)} {m.formula!r}: {ex!r}") from ex
        self.grid[g.sheet][m.row, m.col] = value

    def _desc_arg(self, d: RefDesc, m: _Member) -> Ranges:
        sheet, r1, c1, r2, c2 = d.rect(m.row, m.col)
        ref = f"{_sheet_prefix(sheet)}{_a1(r1, c1)}:{_a1(r2, c2)}"
        return Ranges().push(ref, self.grid[sheet][r1:r2 + 1, c1:c2 + 1].copy())

    _name_arg = _desc_arg

    def _ranges_arg(self, template: Ranges, rects) -> Ranges:
        values = {}
        for r, (sheet, r1, c1, r2, c2) in zip(template.ranges, rects):
            values[r["name"]] = (r, self.grid[sheet][r1:r2 + 1, c1:c2 + 1].copy())
        return Ranges(template.ranges, values)

    def cell_order(self, gids: set[int]) -> list[tuple[int, int]]:
        """Members of mutually dependent groups in dependency order (iterative DFS)."""
        def deps(gid, i):
            found = []
            for sheet, r1, c1, r2, c2 in self.groups[gid].reads(i):
                owner = self.owner[sheet][r1:r2 + 1, c1:c2 + 1]
                member = self.member[sheet][r1:r2 + 1, c1:c2 + 1]
                mask = np.isin(owner, list(gids))
                found += zip(owner[mask].tolist(), member[mask].tolist())
            return found

        order, state = [], {}
        for gid in sorted(gids):
            for i in range(len(self.groups[gid].members)):
                if (gid, i) in state:
                    continue
                state[(gid, i)] = 1
                work = [((gid, i), iter(deps(gid, i)))]
                while work:
                    node, it = work[-1]
                    for nxt in it:
                        s = state.get(nxt)
                        if s == 1:
                            g = self.groups[nxt[0]]
                            m = g.members[nxt[1]]
                            raise CircularReferenceError(
                                f"circular reference through {g.sheet}!{_a1(m.row, m.col)}")
                        if s is None:
                            state[nxt] = 1
                            work.append((nxt, iter(deps(*nxt))))
                            break
                    else:
                        work.pop()
                        state[node] = 2
                        order.append(node)
        self.stats["cyclic_cells"] += len(order)
        return order

    # ---- 7. output
    def _values(self) -> dict[tuple[str, str], object]:
        out = {}
        for sheet, consts in self.constants.items():
            for (r, c), v in consts.items():
                out[(sheet, _a1(r, c))] = _public_value(v, False)
        for g in self.groups:
            grid = self.grid[g.sheet]
            for m in g.members:
                out[(g.sheet, _a1(m.row, m.col))] = _public_value(grid[m.row, m.col], True)
        return out


def _per_row(func, batch: _Batch, args: list, n: int, takes_inputs: bool) -> np.ndarray | None:
    """One call of a vector-compiled function over n rows: its n results (an object array), or
    None where the call fails or does not give one value per row (a formula without inputs
    gives one value, which every row shares)."""
    batch.n = n
    try:
        out = _replace_empty(np.asarray(_call(func, args), dtype=object))
    except Exception:   # e.g. _NotScalar: the per-cell path reports real errors
        return None
    finally:
        batch.n = 1
    flat = out.reshape(-1)
    if not (out.size == n or (out.size == 1 and not takes_inputs)) \
            or any(isinstance(v, np.ndarray) for v in flat):
        return None
    values = np.empty(n, object)
    values[:] = list(flat) if out.size == n else [flat[0]] * n
    return values


def _closure(start: set[int], edges: dict[int, set[int]]) -> set[int]:
    """Every node reached from `start` along `edges` (start included)."""
    reached, todo = set(start), list(start)
    while todo:
        for nxt in edges.get(todo.pop(), ()):
            if nxt not in reached:
                reached.add(nxt)
                todo.append(nxt)
    return reached


def _same_cells(desc: RefDesc, template, rep: _Member, host_sheet: str, refs: References) -> bool:
    """Does the compiled input's own range equal the descriptor at the representative cell?"""
    if template is None:   # a defined name: formulas leaves it unresolved
        return True
    if not isinstance(template, Ranges) or len(template.ranges) != 1:
        return False
    r = template.ranges[0]
    sid = r.get("sheet_id") or ""
    sid = sid[1:-1].replace("''", "'") if sid.startswith("'") else sid
    sheet = refs.titles.get(sid.upper()) if sid else host_sheet
    return (sheet, int(r["r1"]), r["n1"], int(r["r2"]), r["n2"]) == desc.rect(rep.row, rep.col)


def cells_read(wb, cells) -> dict[tuple[str, str], list[tuple]]:
    """For each (sheet, cell) holding a formula: the rectangles (sheet, top, left, bottom,
    right) it reads directly, through references and defined names (the lexer's reading). A
    reference the workbook cannot resolve is left out: this serves reports, not evaluation."""
    refs = References.of(wb)
    out = {}
    for sheet, coordinate in cells:
        cell = wb[sheet][coordinate]
        try:
            text = _formula_text(cell)
        except UnsupportedFormulaError:
            continue
        rects = []
        for m in _LEXER.finditer(text):
            kind = m.lastgroup
            if kind == "ident" and m["call"]:
                continue
            if kind in ("ref", "ident"):
                with contextlib.suppress(UnsupportedFormulaError):
                    rects.append(refs.ref(m[kind], sheet, cell.row, cell.column)
                                 .rect(cell.row, cell.column))
        out[(sheet, coordinate)] = rects
    return out


def _formula_text(cell) -> str:
    value = cell.value
    if not isinstance(value, str):
        ref = getattr(value, "ref", None)
        text = getattr(value, "text", None)
        if text is None or (ref and ":" in str(ref) and len(set(str(ref).split(":"))) > 1):
            raise UnsupportedFormulaError(
                f"{cell.parent.title}!{cell.coordinate}: array/data-table formula {value!r}")
        value = text
    value = value.replace("\n", "")  # as formulas' Parser does
    return value[1:] if value.startswith("==") else value


def _constant(cell, excel_model: bool = False):
    """A constant as it reads after a save (openpyxl writes numbers as '%.16g'); with
    `excel_model`, floats rounded to 15 decimals as ExcelModel rounds them."""
    value, kind = cell.value, cell.data_type
    if kind == "n" and not isinstance(value, bool):
        text = _number_text(value)
        if text == "":
            return None  # NaN and infinities are written as empty cells
        value = float(text) if any(ch in text for ch in ".eE") else int(text)
        return round(value, 15) if excel_model and isinstance(value, float) else value
    if value == "":
        return None  # saved as an empty inline string, read back as no value
    if kind == "e":
        return Error.errors.get(str(value).upper(), value)
    if isinstance(value, np.generic):
        return value.item()
    return value


def _number_text(value) -> str:
    """A number as openpyxl saves it ('%.16g'; '' for NaN and infinities)."""
    if math.isnan(value) or math.isinf(value):
        return ""
    return "%.16g" % value


def _sheet_prefix(sheet: str) -> str:
    return "'" + sheet.upper().replace("'", "''") + "'!"


def _a1(row: int, col: int) -> str:
    return f"{column_letter(int(col))}{int(row)}"
