"""One domain for build and verify: what build accepts, its own verify reads the same way.

The mechanism language's expressions are read twice: by the writer (language.expressions,
through Python's parser) and by verify's independent reference (check.reference.expressions, a
parser of its own). A number or a symbol the writer accepts must be one the reference reads as
the same value; what the reference would not read, the writer refuses.
"""
from __future__ import annotations

import copy
import math
import tomllib

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

import linkbook
from conftest import examples, ROOT
from linkbook.base.errors import InputError
from linkbook.book import builder
from linkbook.check.reference.expressions import evaluate
from linkbook.language import templates
from linkbook.language.expressions import expression
from linkbook.language.model import DescriptionError

SYMBOLS = {"a2": 3.0, "b3": 0.5}


def _built(text: str) -> float | None:
    """The number the writer puts in the book for `text`, or None if it refuses the text."""
    try:
        excel = expression("f", text, set(SYMBOLS)).text
    except DescriptionError:
        return None
    for symbol, value in SYMBOLS.items():
        excel = excel.replace(f"{{{symbol}}}", repr(value))
    return eval(excel.replace("^", "**"))   # + - * / ^ and numbers only (no functions drawn)


def _read(text: str) -> float | None:
    try:
        return float(evaluate(text, SYMBOLS))
    except ValueError:
        return None


@pytest.mark.parametrize("text", ["-1_000", "0x10", "0o7", "0b1", "1j", "１０", "١٠", "ａ2",
                                  "1e5", "1.", ".5", "2.5E+3", "a2*1e-3", "00"])
def test_a_number_the_writer_accepts_is_one_the_reference_reads_alike(text):
    built = _built(text)
    if built is not None:
        assert _read(text) == pytest.approx(built, rel=1e-15), text


def test_the_spellings_python_alone_reads_are_refused():
    """The reference reads none of these (so verify refused the book build wrote)."""
    for text in ["-1_000", "0x10", "0o7", "0b1", "１０", "١٠", "ａ2"]:
        assert _read(text) is None, text
        assert _built(text) is None, text


@given(st.text(alphabet="0123456789._eE+-*/ xob()a2١０ａj", min_size=1, max_size=12))
@settings(max_examples=examples(300), deadline=None)
def test_random_spellings_the_writer_accepts_the_reference_reads_alike(text):
    try:
        built = _built(text)
    except (ZeroDivisionError, OverflowError):
        return          # an error value in both (the reference's NaN): not the spelling's
    if built is not None and math.isfinite(built):
        read = _read(text)
        assert read is not None and read == pytest.approx(built, rel=1e-12, abs=1e-300), text


# ---------------------------------------------------------------- random templates
# The four-bar with random extra parameters (their symbols and Excel names drawn among fresh
# ones and, now and then, the book's own in any case) and random loads: expressions of numbers,
# parameters, the steps' columns, + - * /, IF and IFERROR, now and then one build must refuse
# (a number verify would not read, an error on every row, a comparison). Every
# template build accepts must give a book its own verify passes; the rest are refused in one
# line (InputError) before anything is written.
EXAMPLES = examples(30)
FOURBAR = tomllib.loads((ROOT / "templates" / "fourbar.toml").read_text(encoding="utf-8"))
OWN_NAMES = ["theta12_now", "TO_METRES", "to_metres", "speed_fluctuation", "k_rpm_in", "K_Gamma"]
COLUMNS = ["xB", "yC", "theta12", "xA"]

identifiers = st.from_regex(r"[a-z][a-z0-9]{0,5}_[a-z0-9]{1,4}", fullmatch=True)
numbers = st.one_of(st.floats(0.001, 50).map(lambda v: f"{v:.6g}"),
                    st.sampled_from(["2.5e1", "1e-3", "3.", ".25", "2E+1"]))
# what build must refuse: numbers verify would not read, errors on every row, TRUE or FALSE
BAD = ["1_0", "0x10", "NA()", "1/0", "T4 == T4", "xB*NA()", "IF(xB > 0, 1/0, NA())"]


def rarely(common, rare):
    """`rare` one time in eight."""
    return st.integers(0, 7).flatmap(lambda i: rare if i == 5 else common)   # 0 comes often


def _expressions(symbols: list[str]):
    atoms = st.one_of(numbers, st.sampled_from(symbols + COLUMNS))

    def grow(inner):
        return st.one_of(
            st.tuples(inner, st.sampled_from(["+", "-", "*"]), inner).map(" ".join),
            st.tuples(inner, numbers).map(lambda p: f"({p[0]})/{p[1]}"),
            st.tuples(inner, inner).map(lambda p: f"IF({p[0]} > 12.345, {p[0]}, {p[1]})"),
            inner.map(lambda x: f"IFERROR({x}, NA())"),
            inner.map(lambda x: f"IFERROR(NA(), {x})"))
    return rarely(st.recursive(atoms, grow, max_leaves=5), st.sampled_from(BAD))


def _name():
    return rarely(identifiers, st.sampled_from(OWN_NAMES))


@st.composite
def random_templates(draw) -> dict:
    data = copy.deepcopy(FOURBAR)
    data["sweep"]["step"] = 30
    params = data["parameters"]
    symbols = ["T4"]
    for _ in range(draw(st.integers(0, 3))):
        symbol = draw(_name())
        entry = {"label": "extra load", "unit": "N·m", "kind": "torque",
                 "value": draw(st.floats(-5, 5).map(lambda v: round(v, 3)))}
        if draw(st.booleans()):
            entry["name"] = draw(_name())
        params.setdefault(symbol, entry)
        symbols.append(symbol)
    loads = []
    for _ in range(draw(st.integers(1, 4))):
        if draw(st.booleans()):
            loads.append({"body": ["B0", "B"], "torque": draw(_expressions(symbols))})
        else:
            loads.append({"at": draw(st.sampled_from(["A", "B", "C"])),
                          "force": [draw(_expressions(symbols)), draw(_expressions(symbols))]})
    data["mechanism"]["loads"] = loads
    return data


@pytest.mark.slow       # about thirty books built and verified
@given(data=random_templates())
@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck),
          derandomize=True)
def test_every_book_that_builds_verifies(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("one-domain") / "mine.xlsx"
    try:
        builder.build_file(templates.from_data("mine", data, "mine.toml"), path)
    except InputError as exc:
        assert "\n" not in str(exc) and str(exc).startswith("mine.toml: "), str(exc)
        assert not path.exists()
        return
    report = linkbook.verify(path)
    assert report.status == 0, (data["parameters"], data["mechanism"]["loads"],
                                [m for c in report.checks for m in c.mismatches][:3],
                                report.error)
