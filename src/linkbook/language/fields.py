"""Reading a description's fields: tables, text, the keys a table may have, and the names a
description gives (symbols, column keys, points). Each problem raises DescriptionError naming
the field.
"""
from __future__ import annotations

import re

from .model import DescriptionError

IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
POINT_NAME = re.compile(r"^[A-Za-z0-9_]+$")
RESERVED_KEYS = {"closes", "gap_from", "gap_to"}     # the sweep's bookkeeping columns
# How deep a template's tables and lists may nest. The deepest a template needs is 5
# (mechanism.steps[1].columns.xs.key); the checks that follow, and the messages that show a
# value, recurse once per level, so data nested thousands deep is refused before them.
NESTING_LIMIT = 32


def check_nesting(field: str, data: object) -> None:
    """Refuse tables and lists nested deeper than NESTING_LIMIT, naming the path down to the
    first level too many (from `field`, or from the first key where `field` is ""); a walk
    without recursion."""
    todo = [(data, field, 0)]
    while todo:
        value, where, depth = todo.pop()
        if depth > NESTING_LIMIT:
            raise DescriptionError(where, f"tables and lists nest more than {NESTING_LIMIT} "
                                          "deep here; a template needs at most a few levels")
        if isinstance(value, dict):
            todo.extend((v, f"{where}.{k}" if where else str(k), depth + 1)
                        for k, v in value.items())
        elif isinstance(value, list):
            todo.extend((v, f"{where}[{i}]", depth + 1) for i, v in enumerate(value))


def as_table(field: str, value: object) -> dict:
    if not isinstance(value, dict):
        raise DescriptionError(field, f"must be a table (got {value!r})")
    return value


def as_text(field: str, value: object) -> str:
    if not isinstance(value, str) or not value.strip():
        raise DescriptionError(field, f"must be non-empty text (got {value!r})")
    return value


def check_keys(field: str, table: dict, required: set, optional: set) -> None:
    for k in sorted(required):
        if k not in table:
            raise DescriptionError(f"{field}.{k}", "is missing")
    for k in table:
        if k not in required | optional:
            known = ", ".join(sorted(required | optional))
            raise DescriptionError(f"{field}.{k}", f"is not a key here; known: {known}")
