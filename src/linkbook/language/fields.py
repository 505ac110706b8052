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
