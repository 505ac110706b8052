"""The one adapter to `formulas`' internals: its patches at import (its function modules imported
without scipy; Excel 2010's AGGREGATE added), its parser and tokenizer, a formula's graph
compiled into a call of its function nodes (Pipe), and its ExcelModel as the slow reference
evaluation (evaluate_formulas_model)."""
from __future__ import annotations

import contextlib
import functools
import graphlib
import io
import itertools
import math
import operator
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import schedula as sh
from formulas.errors import AnchorRangeName, InvalidRangeName
from formulas.functions import (COMPILING, FUNCTIONS, flatten, get_functions, parse_ranges,
                                replace_empty, wrap_func)
from formulas.functions.operators import OPERATORS
from formulas.ranges import Ranges
from formulas.tokens.function import Function
from formulas.tokens.operand import Error, Range, XlError
from formulas.tokens.operator import Intersect, OperatorToken

from . import grammar
from .errors import UnsupportedFormulaError
from .vector import Batch, wrap

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
    all its function modules; its statistics module imports scipy at its top (a slow import,
    ahead of any book's first formula) for functions no linkbook book uses, and its math module
    reads numpy.random (RAND) at its top, which imports numpy.random.  They are imported here
    with scipy and numpy.random standing in: the same functions, and the real module imported
    the first time one of them needs it."""
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
    """formulas' parser, imported on first use: the engine's grammar reads what linkbook writes,
    and the parser's modules are slow to import."""
    from formulas import Parser
    return Parser()


@dataclass
class TokenInfo:
    """What the `formulas` tokenizer says about one formula."""
    spans: list[tuple[int, int]]
    keys: list[str]            # Range token names, e.g. 'SWEEP!D8', 'A_3' (the compiled inputs)
    functions: set[str]
    builder: object


def tokenize(formula: str) -> TokenInfo:
    """References, keys and functions of a formula, with its graph: the engine's grammar's reading
    where the formula is in that grammar, else `formulas`' parser's."""
    parsed = grammar.parse(formula, plain_functions())
    if parsed is not None:
        info = TokenInfo(parsed.spans, parsed.keys, set(parsed.functions), parsed)
    else:
        info = formulas_tokenize(formula)
    bad = info.functions & DYNAMIC
    if bad:
        raise UnsupportedFormulaError(f"{', '.join(sorted(bad))} cannot be evaluated here (its "
                                      f"result depends on more than the cells it names)")
    return info


@functools.lru_cache(maxsize=1)
def plain_functions() -> frozenset[str]:
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


def formulas_tokenize(formula: str) -> TokenInfo:
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


def compile_formula(graph, batch: Batch | None = None, host: Ranges | None = None):
    """Compile a parsed formula (a grammar.Parsed or a `formulas` AstBuilder); with `batch`,
    every node is wrapped for vector calls."""
    extra = {_cell_token(): host} if host is not None else {}
    if isinstance(graph, grammar.Parsed):
        return Pipe.of_parsed(graph, batch, extra)
    _wrap_nodes(graph, batch)
    return Pipe.of(graph, extra) or graph.compile(**extra)


def _wrap_nodes(builder, batch: Batch | None) -> None:
    for node_id, node in builder.dsp.function_nodes.items():
        node["function"] = wrap(node["function"], re.sub(r"<\d+>$", "", node_id), batch)


def _formulas_graph(formula: str, batch: Batch | None, extra: dict):
    """The graph `formulas` compiles for a formula (a pipe's fallback)."""
    builder = _parser().ast(formula)[1]
    _wrap_nodes(builder, batch)
    return builder.compile(**extra)


def _input_templates(keys) -> dict:
    """compile()'s inputs for the references and names a formula reads: each key, in sorted
    order, with its range (None for a defined name)."""
    return {k: _input_template(k) for k in sorted(keys)}


@functools.lru_cache(maxsize=4096)
def _input_template(key: str):
    """compile()'s input for one key, made once per key: many formulas read one cell (a
    position's, a name's), and reading a reference's text is formulas' regex. The Ranges is
    shared: it is only read (a reference's parts), never given a value."""
    try:
        return Ranges().push(key)
    except AnchorRangeName:
        return sh.NONE
    except InvalidRangeName:
        return None


def ranges_of(ref: str, value) -> Ranges:
    """Ranges().push(ref, value) for a reference the engine wrote (`'S'!B5:B9`), its parts
    read once per text."""
    return Ranges().set_value(dict(_range_parts(ref)), value)


_range_parts = functools.lru_cache(maxsize=4096)(Ranges.get_range)


class Pipe:
    """A parsed formula's function nodes called one after the other in dependency order: the
    same functions on the same arguments as the graph `formulas` compiles, without building
    schedula's dispatcher (most of the cost of compiling) or running its dispatch (slow for a
    call of a few operations).  `inputs` are the ones `compile()` gives: every reference and
    name the formula reads, in sorted order, with its range.  A constant part is computed at
    each call, not once.  A node that gives no value sends the call to the compiled graph."""

    def __init__(self, graph, inputs, steps, defaults, output):
        self.graph, self.compiled = graph, None     # graph(): the compiled graph, on demand
        self.inputs = inputs
        self.steps = steps
        self.defaults = defaults
        self.output = output

    @classmethod
    def of(cls, builder, extra: dict) -> "Pipe | None":
        """The pipe of builder's graph, or None where it takes more than a plain order: a node
        with several outputs or options, a function that behaves otherwise while compiling, an
        operator on references.  A lone reference, name or constant is a pipe of no steps."""
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
        if (functions and output not in producer) or any(
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
    def of_parsed(cls, parsed: grammar.Parsed, batch: Batch | None,
                  extra: dict) -> "Pipe":
        """The pipe of grammar's graph: its nodes in their order (each after its arguments),
        with the functions `formulas`' tokens compile to.  A lone reference, name or constant
        is a pipe of no steps: its result is compile()'s, the value through the output's
        filter."""
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
                steps.append((wrap(func, name, batch), tuple(ids[a] for a in args), i))
                ids.append(i)
        formula = parsed.formula
        return cls(lambda: _formulas_graph(formula, batch, extra), _input_templates(keys),
                   steps, defaults, ids[-1])

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


def call(func, args):
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


def empty_as_zero(out: np.ndarray) -> np.ndarray:
    """replace_empty (EMPTY -> 0), skipping its element-wise == scan when nothing is EMPTY (an
    identity test of each element, in C: a vector call's result is thousands of them)."""
    if any(map(operator.is_, out.reshape(-1).tolist(), itertools.repeat(sh.EMPTY))):
        return np.asarray(replace_empty(out), dtype=object)
    return out


def cell_result(out):
    """A compiled formula's output as ExcelModel stores it for one cell."""
    return Ranges().set_value(dict(_ONE_CELL), replace_empty(out)).value[0, 0]


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
        out[cell] = public_value(value, cell in formula_cells)
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


def public_value(value, is_formula: bool):
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
