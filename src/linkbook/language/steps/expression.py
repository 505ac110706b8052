"""The expression step: a column (or a constant) of the user's own formula. It gets no rates: a
formula of the user's has no derivative written for it.
"""
from __future__ import annotations

from ..columns import Sym
from ..expressions import expression
from ..fields import as_text
from ..model import CONSTANT, LENGTH, RAD, DescriptionError, Quantity
from .step_type import StepType, schema_keys

UNITS = {"length": LENGTH, "rad": RAD, "-": "-"}


def place(c, field: str, s: dict) -> None:
    """The user's formula of parameters and earlier columns, #N/A where its value is an error."""
    k = c.new_key(f"{field}.key", s["key"])
    unit = s.get("unit", "-")
    if unit not in UNITS:
        raise DescriptionError(f"{field}.unit", f"must be one of {', '.join(UNITS)} "
                                                f"(got {unit!r})")
    shown = s.get("shown", True)
    if not isinstance(shown, bool):
        raise DescriptionError(f"{field}.shown", "must be true or false")
    known = c.symbols | c.swept | {q.key for q in c.model.quantities}
    body = expression(f"{field}.formula", s["formula"], known)
    if "time_ratio_of" in s:
        of = s["time_ratio_of"]
        if not isinstance(of, str) or of not in {q.key for q in c.model.quantities}:
            raise DescriptionError(f"{field}.time_ratio_of",
                                   f"must be the key of an earlier column (got {of!r})")
    formula = f"IFERROR({body.text},NA())"
    sym = Sym(k, as_text(f"{field}.symbol", s.get("symbol", k)),
              as_text(f"{field}.label", s.get("label", k)), shown=shown)
    role = c.role(formula, sym)
    if "time_ratio_of" in s and role != CONSTANT:
        raise DescriptionError(f"{field}.time_ratio_of", "a time ratio is one number per "
                                                         "book: the formula must be shown and "
                                                         "depend on the parameters alone")
    c.model.add(Quantity(k, sym.symbol, UNITS[unit], formula, role, sym.label))


def dimensions(step: dict) -> dict[str, int]:
    """The formula stands for a length where its unit says so, else for a number."""
    return {"formula": int(step.get("unit") == "length")}


STEP = StepType(schema_keys("expression"), place, None, dimensions)
