"""What a template may contain: the JSON Schema shipped beside this module
(mechanism.schema.json; docs/ holds a copy for editors). A template is checked against it first,
each problem reported as one line naming the file and the field; the semantic checks of
templates.py and compiler.py follow.

jsonschema judges and words every problem. Importing it costs more than the rest of a small
build's checks, so a template is first read by `fits`, a plain reading of the few keywords the
schema uses: when it is sure the template fits, jsonschema is not needed; whenever it is not sure
(a keyword or a value it does not know), or the template does not fit, jsonschema decides.
"""
from __future__ import annotations

import json
import re
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
    if fits(data) is True:
        return None
    errors = list(_validator().iter_errors(data))
    if not errors:
        return None
    # a missing key last: a misspelt key, reported as unknown with its suggestion, explains it
    return _describe(min(errors, key=lambda e: e.validator == "required"), data)


# ---------------------------------------------------------------- the quick reading
class _Unsure(Exception):
    """The quick reading cannot tell as jsonschema would: jsonschema decides."""


def fits(data) -> bool | None:
    """Whether `data` fits the schema, as jsonschema's Draft 7 validator judges it; None where
    this reading is not sure (then only jsonschema can tell)."""
    try:
        return _fits(data, schema())
    except _Unsure:
        return None


# Keywords that validate nothing by themselves ("then" and "else" are read with their "if")
_INERT = {"$schema", "$id", "$comment", "title", "description", "default", "examples", "then",
          "else"}
# The Python types a TOML (or JSON) reader gives; any other value leaves the reading unsure
_PLAIN = (dict, list, str, bool, int, float, type(None))


def _fits(value, part) -> bool:
    if part is True or part is False:
        return part
    for keyword, want in part.items():
        if keyword in _INERT:
            continue
        check = _KEYWORDS.get(keyword)
        if check is None:
            raise _Unsure(keyword)
        if not check(value, want, part):
            return False
    return True


def _is_type(value, name: str) -> bool:
    if type(value) not in _PLAIN:
        raise _Unsure(type(value).__name__)
    if name in ("number", "integer"):
        if isinstance(value, bool):                  # bool is an int in Python, not in JSON
            return False
        if isinstance(value, float) and name == "integer":
            raise _Unsure("a float where a whole number is wanted")   # 3.0 is one in Draft 7
        return isinstance(value, (int, float))
    kinds = {"object": dict, "array": list, "string": str, "boolean": bool, "null": type(None)}
    if name not in kinds:
        raise _Unsure(name)
    return isinstance(value, kinds[name])


def _equal(one, two) -> bool:
    """jsonschema's equality of two values: True and 1 differ, 1 and 1.0 do not."""
    if one is two:
        return True
    if isinstance(one, str) or isinstance(two, str):
        return one == two
    if type(one) not in _PLAIN or type(two) not in _PLAIN:
        raise _Unsure(f"{type(one).__name__} compared with {type(two).__name__}")
    if isinstance(one, list) and isinstance(two, list):
        return len(one) == len(two) and all(map(_equal, one, two))
    if isinstance(one, dict) and isinstance(two, dict):
        return len(one) == len(two) and all(key in two and _equal(value, two[key])
                                            for key, value in one.items())
    return isinstance(one, bool) == isinstance(two, bool) and one == two


def _type(value, want, part) -> bool:
    return any(_is_type(value, name) for name in ([want] if isinstance(want, str) else want))


def _properties(value, want, part) -> bool:
    return not isinstance(value, dict) or all(
        _fits(value[key], sub) for key, sub in want.items() if key in value)


def _additional_properties(value, want, part) -> bool:
    if not isinstance(value, dict):
        return True
    if "patternProperties" in part:
        raise _Unsure("patternProperties")
    known = part.get("properties", {})
    return all(_fits(value[key], want) for key in value if key not in known)


def _items(value, want, part) -> bool:
    if not isinstance(want, dict | bool):
        raise _Unsure("items as a list of schemas")
    return not isinstance(value, list) or all(_fits(item, want) for item in value)


def _if(value, want, part) -> bool:
    branch = part.get("then", True) if _fits(value, want) else part.get("else", True)
    return _fits(value, branch)


def _number_check(test):
    return lambda value, want, part: not _is_type(value, "number") or test(value, want)


def _object_check(test):
    return lambda value, want, part: not isinstance(value, dict) or test(value, want)


def _array_check(test):
    return lambda value, want, part: not isinstance(value, list) or test(value, want)


_KEYWORDS = {
    "type": _type,
    "properties": _properties,
    "additionalProperties": _additional_properties,
    "required": _object_check(lambda value, want: all(key in value for key in want)),
    "minProperties": _object_check(lambda value, want: len(value) >= want),
    "propertyNames": _object_check(lambda value, want: all(_fits(key, want) for key in value)),
    "items": _items,
    "minItems": _array_check(lambda value, want: len(value) >= want),
    "maxItems": _array_check(lambda value, want: len(value) <= want),
    "pattern": lambda value, want, part: not isinstance(value, str) or
    re.search(want, value) is not None,
    "exclusiveMinimum": _number_check(lambda value, want: value > want),
    "minimum": _number_check(lambda value, want: value >= want),
    "maximum": _number_check(lambda value, want: value <= want),
    "const": lambda value, want, part: _equal(value, want),
    "enum": lambda value, want, part: any(_equal(value, option) for option in want),
    "anyOf": lambda value, want, part: any(_fits(value, sub) for sub in want),
    "allOf": lambda value, want, part: all(_fits(value, sub) for sub in want),
    "oneOf": lambda value, want, part: sum(_fits(value, sub) for sub in want) == 1,
    "if": _if,
    "not": lambda value, want, part: not _fits(value, want),
}


# ---------------------------------------------------------------- wording a problem
@cache
def _mechanism_key_validator(key: str):
    import jsonschema
    return jsonschema.Draft7Validator(schema()["properties"]["mechanism"]["properties"][key])


def mechanism_key_problem(key: str, value: object) -> tuple[str, str] | None:
    """The first problem of one key of a [mechanism] table (one a workbook's record gave back,
    which no template's schema check has seen) as (field, message), or None when it fits."""
    part = schema()["properties"]["mechanism"]["properties"][key]
    try:
        if _fits(value, part):        # the quick reading: jsonschema only for a problem
            return None
    except _Unsure:
        pass
    errors = list(_mechanism_key_validator(key).iter_errors(value))
    if not errors:
        return None
    field, message = _describe(min(errors, key=lambda e: e.validator == "required"), value)
    where = f"mechanism.{key}"
    joined = f"{where}{field}" if field.startswith("[") or not field else f"{where}.{field}"
    return joined, message


def _one_alternative(error):
    """Of an anyOf's or oneOf's failure on a table, the error of the one alternative that is a
    table (a polar force's, not the [Fx, Fy] list): what went wrong inside it, such as a
    misspelt key; None when no single alternative is meant (a list keeps the description of
    every alternative)."""
    if error.validator not in ("anyOf", "oneOf") or not error.context or \
            not isinstance(error.instance, dict):
        return None
    wrong_type = {e.relative_schema_path[0] for e in error.context
                  if e.validator == "type" and not e.relative_path}
    meant = [e for e in error.context if e.relative_schema_path[0] not in wrong_type]
    if len({e.relative_schema_path[0] for e in meant}) != 1:
        return None
    return min(meant, key=lambda e: e.validator == "required")


def _shown(value) -> str:
    """A value as a message quotes it: a table by its keys, never as a Python dict."""
    if isinstance(value, dict):
        keys = [str(k) for k in value]
        return ("an empty table" if not keys else
                f"a table of {', '.join(keys[:-1])} and {keys[-1]}" if len(keys) > 1 else
                f"a table of {keys[0]}")
    return repr(value)


def _describe(error, data: dict) -> tuple[str, str]:
    inner = _one_alternative(error)
    if inner is not None:
        return _describe(inner, data)
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
        import difflib
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
        return field, f"must be {described} (got {_shown(got)})"
    return field, error.message


def _suggest(word: str, known: set[str], missing: list[str]) -> str:
    """The key `word` was likely meant to be: a missing one first (a misspelt required key),
    else any known one."""
    import difflib
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
