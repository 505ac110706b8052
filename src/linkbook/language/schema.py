"""What a template may contain: the JSON Schema shipped beside this module
(mechanism.schema.json; docs/ holds a copy for editors). A template is checked against it first,
each problem reported as one line naming the file and the field; the semantic checks of
templates.py and compiler.py follow.
"""
from __future__ import annotations

import difflib
import json
from functools import cache
from pathlib import Path

SCHEMA_PATH = Path(__file__).resolve().parent / "mechanism.schema.json"

# What a reader calls each JSON type
_TYPE_WORDS = {"object": "a table", "array": "a list", "string": "text", "number": "a number",
               "integer": "a whole number", "boolean": "true or false"}


@cache
def schema() -> dict:
    return json.loads(SCHEMA_PATH.read_text(encoding="utf-8"))


@cache
def _validator():
    import jsonschema
    return jsonschema.Draft7Validator(schema())


def step_schemas() -> dict[str, dict]:
    """Each step type's schema: {"crank": {...}, "dyad": {...}, ...}."""
    items = schema()["properties"]["mechanism"]["properties"]["steps"]["items"]
    return {rule["if"]["properties"]["type"]["const"]: rule["then"] for rule in items["allOf"]}


def keys_of(part: dict) -> tuple[set[str], set[str]]:
    """(required keys, optional keys) of an object's schema."""
    required = set(part.get("required", ()))
    return required, set(part.get("properties", {})) - required


def problem(data: dict) -> tuple[str, str] | None:
    """The first problem of a template's data as (field, message), or None when it fits."""
    errors = list(_validator().iter_errors(data))
    if not errors:
        return None
    # a missing key last: a misspelt key, reported as unknown with its suggestion, explains it
    return _describe(min(errors, key=lambda e: e.validator == "required"), data)


@cache
def _mechanism_key_validator(key: str):
    import jsonschema
    return jsonschema.Draft7Validator(schema()["properties"]["mechanism"]["properties"][key])


def mechanism_key_problem(key: str, value: object) -> tuple[str, str] | None:
    """The first problem of one key of a [mechanism] table (one a workbook's record gave back,
    which no template's schema check has seen) as (field, message), or None when it fits."""
    errors = list(_mechanism_key_validator(key).iter_errors(value))
    if not errors:
        return None
    field, message = _describe(min(errors, key=lambda e: e.validator == "required"), value)
    where = f"mechanism.{key}"
    joined = f"{where}{field}" if field.startswith("[") or not field else f"{where}.{field}"
    return joined, message


def _describe(error, data: dict) -> tuple[str, str]:
    path = list(error.absolute_path)
    field = field_name(path, data)
    kind, want, got = error.validator, error.validator_value, error.instance
    part = error.schema
    if kind == "additionalProperties":
        known = set(part.get("properties", {}))
        extra = [k for k in got if k not in known]
        missing = [k for k in part.get("required", ()) if k not in got]
        return field, f"unknown key {extra[0]!r}{_suggest(extra[0], known, missing)}"
    if kind == "required":
        missing = next(k for k in want if k not in got)
        near = difflib.get_close_matches(missing, [k for k in got if isinstance(k, str)], n=1)
        hint = f" ({near[0]!r} is not a key: did you mean {missing!r}?)" if near else ""
        return _join(field, missing), f"is missing{hint}"
    if "propertyNames" in error.schema_path:       # a key of the table, not a value
        return _join(field, str(got)), ("is not a symbol: letters, digits and _, starting "
                                        "with a letter")
    described = part.get("description")
    if kind == "type":
        types = [want] if isinstance(want, str) else want
        return field, f"must be {' or '.join(_TYPE_WORDS.get(t, t) for t in types)} (got {got!r})"
    if kind in ("enum", "const") and not described:
        options = want if kind == "enum" else [want]
        return field, f"must be one of {', '.join(map(str, options))} (got {got!r})"
    if kind == "minProperties":
        return field, "needs at least one entry"
    if kind == "exclusiveMinimum":
        return field, f"must be greater than {want} (got {got!r})"
    if kind == "minItems" and not described:
        return field, f"must have at least {want} {'entry' if want == 1 else 'entries'} (got {got!r})"
    if described:
        return field, f"must be {described} (got {got!r})"
    return field, error.message


def _suggest(word: str, known: set[str], missing: list[str]) -> str:
    """The key `word` was likely meant to be: a missing one first (a misspelt required key),
    else any known one."""
    near = difflib.get_close_matches(word, missing, n=1) or \
        difflib.get_close_matches(word, sorted(known), n=1)
    return f" (did you mean {near[0]!r}?)" if near else f"; known: {', '.join(sorted(known))}"


def _join(field: str, key: str) -> str:
    return f"{field}.{key}" if field else key


def field_name(path: list, data: dict) -> str:
    """mechanism.steps[1] (dyad B).p_length: the path of a field, a step named by its type and
    point (or key), as the semantic checks name it."""
    out, here = "", data
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out = _join(out, part)
        here = here[part] if isinstance(here, (dict, list)) else None
        if isinstance(part, int) and out.endswith(f"steps[{part}]") and isinstance(here, dict):
            label = here.get("point") or here.get("key")
            if isinstance(label, str):
                out += f" ({here.get('type', 'step')} {label})"
    return out
