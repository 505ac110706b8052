"""What a formula reads: its references as descriptors relative to the host cell (RefDesc), the
workbook's sheets and defined names (References), a formula's shape (every reference in R1C1
form with its sheet) found by a regex lexer, its text as a template that copies shift, and
the formula text and constants of openpyxl cells as a saved file holds them."""
from __future__ import annotations

import contextlib
import functools
import math
import re
from dataclasses import dataclass

import numpy as np
from formulas.tokens.operand import Error

from .errors import UnsupportedFormulaError
from ..base.xlsx import column_index, column_letter

MAX_ROW, MAX_COL = 1048576, 16384


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

    @functools.cached_property
    def _down_format(self) -> tuple[str, tuple[int, ...], int, int]:
        """_down as one format string with a field for each relative row, those rows, and
        their smallest and largest (a copy down the column is one format call)."""
        texts, rows = self._down
        escaped = [t.replace("{", "{{").replace("}", "}}") for t in texts]
        return "{}".join(escaped), rows, min(rows, default=0), max(rows, default=0)

    def copied_down(self, origin: int, rows: list[int], texts: list[str], start: int) -> int:
        """How far from `start` the `texts` (of cells in this formula's column, at `rows`) are
        this formula, written at row `origin`, copied down: the index of the first that is not
        (shifted(row - origin, 0) != its text), or len(texts). shifted's copy down is written out
        here, not called: this is the grouping's innermost loop, a turn per formula cell."""
        text, slots, lowest, highest = self._down_format
        write = text.format
        i, end = start, len(texts)
        while i < end:
            dr = rows[i] - origin
            if slots and (lowest + dr < 1 or highest + dr > MAX_ROW) \
                    or write(*[row + dr for row in slots]) != texts[i]:
                break
            i += 1
        return i

    def shifted(self, dr: int, dc: int) -> str | None:
        """The text of this formula copied dr rows down and dc columns right (None if a
        reference would leave the sheet)."""
        if dc == 0:
            text, rows, lowest, highest = self._down_format
            if rows and (lowest + dr < 1 or highest + dr > MAX_ROW):
                return None
            return text.format(*map(dr.__add__, rows))
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
        equal formula_shape() over the tokenizer's spans; Grouper.group checks one cell per
        group."""
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


def lex_spans(formula: str, refs: References) -> list[tuple[int, int]]:
    """Spans of references and defined names found by the regex lexer."""
    spans = []
    for m in _LEXER.finditer(formula):
        if m["ref"] is not None:
            spans.append(m.span("ref"))
        elif m["ident"] is not None and m["call"] is None and refs.is_name(m["ident"]):
            spans.append(m.span("ident"))
    return spans


def skeleton_of(formula: str, spans) -> str:
    """The formula with every reference replaced by a mark: formulas that differ only in which
    cells they read share a skeleton (and a compiled function)."""
    parts, pos = [], 0
    for start, end in spans:
        parts += [formula[pos:start], "\0"]
        pos = end
    parts.append(formula[pos:])
    return "".join(parts)


def formula_shape(formula, spans, refs: References, sheet, row, col) -> tuple[str, list[RefDesc]]:
    parts, descs, pos = [], [], 0
    for start, end in spans:
        desc = refs.ref(formula[start:end], sheet, row, col)
        parts += [formula[pos:start], desc.canonical()]
        descs.append(desc)
        pos = end
    parts.append(formula[pos:])
    return "".join(parts), descs


def cells_read(wb, cells) -> dict[tuple[str, str], list[tuple]]:
    """For each (sheet, cell) holding a formula: the rectangles (sheet, top, left, bottom,
    right) it reads directly, through references and defined names (the lexer's reading). A
    reference the workbook cannot resolve is left out: this serves reports, not evaluation."""
    refs = References.of(wb)
    out = {}
    for sheet, coordinate in cells:
        cell = wb[sheet][coordinate]
        try:
            text = formula_text(cell)
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


def formula_text(cell) -> str:
    value = cell.value
    if not isinstance(value, str):
        ref = getattr(value, "ref", None)
        text = getattr(value, "text", None)
        if text is None or (ref and ":" in str(ref) and len(set(str(ref).split(":"))) > 1):
            raise UnsupportedFormulaError(
                f"{cell.parent.title}!{cell.coordinate}: array/data-table formula {value!r}")
        value = text
    return formula_of(value)


def formula_of(value: str) -> str:
    """A formula cell's text value as the engine reads it."""
    value = value.replace("\n", "")  # as formulas' Parser does
    return value[1:] if value.startswith("==") else value


def constant_of(value, kind: str, excel_model: bool = False):
    """A cell's constant (its value and data_type) as it reads after a save (openpyxl writes
    numbers as '%.16g'); with `excel_model`, floats rounded to 15 decimals as ExcelModel rounds
    them."""
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


def sheet_prefix(sheet: str) -> str:
    return "'" + sheet.upper().replace("'", "''") + "'!"


def cell_name(row: int, col: int) -> str:
    return f"{column_letter(int(col))}{int(row)}"
