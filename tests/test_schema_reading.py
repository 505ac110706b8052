"""The quick reading of the schema (language/schema.py `fits`) against jsonschema, the third party
that judges templates: wherever the quick reading is sure, it says what jsonschema says, on the
bundled templates and on every one-place damage of them."""
from __future__ import annotations

import copy
import random
import tomllib

import jsonschema
import pytest
from conftest import examples

from linkbook.language import schema, templates

# What a damaged field is set to: every JSON type, numbers JSON and Python see differently
# (True and 1, 3.0 and 3), empty and nested lists and tables
REPLACEMENTS = ["x", "", "fourbar", 0, 1, -1, 2, 1.5, 0.0, 3.0, True, False, None, [], ["a"],
                [1, 2], [[1]], {}, {"a": 1}, {"type": "dyad"}]


# Every one-place damage at the default profile (jsonschema's judgement of each is most of the
# time); a share of them at the fast one, as a property test's examples are sized
SHARE = min(1.0, examples(100) / 100)


def _paths(value, path=()):
    """The path of every value inside a document, the document's own too."""
    yield path
    items = value.items() if isinstance(value, dict) else \
        enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        yield from _paths(item, (*path, key))


def _at(doc, path):
    for key in path:
        doc = doc[key]
    return doc


def _damaged(doc: dict):
    """Each document that differs from `doc` in one place: a value replaced, a key dropped,
    misspelt or added."""
    for path in _paths(doc):
        for new in REPLACEMENTS:
            if path:
                out = copy.deepcopy(doc)
                _at(out, path[:-1])[path[-1]] = copy.deepcopy(new)
                yield out
        here = _at(doc, path)
        if isinstance(here, dict):
            for key in here:
                dropped = copy.deepcopy(doc)
                del _at(dropped, path)[key]
                yield dropped
                misspelt = copy.deepcopy(doc)
                table = _at(misspelt, path)
                table[key + "s"] = table.pop(key)
                yield misspelt
            added = copy.deepcopy(doc)
            _at(added, path)["extra"] = 1
            yield added


def _share(docs, seed: str):
    """SHARE of the documents, drawn with a fixed seed (the same ones in every run): not every
    n-th, which would fall on the same replacement at every path."""
    pick = random.Random(seed)
    return (doc for doc in docs if SHARE >= 1 or pick.random() < SHARE)


def _bundled() -> dict[str, dict]:
    return {p.stem: tomllib.loads(p.read_text(encoding="utf-8")) for p in templates.bundled()}


def test_the_quick_reading_is_sure_that_every_bundled_template_fits():
    """Sure, so a build of a bundled template never needs jsonschema; and right, by jsonschema."""
    validator = jsonschema.Draft7Validator(schema.schema())
    for name, doc in _bundled().items():
        assert validator.is_valid(doc), name
        assert schema.fits(doc) is True, name


@pytest.mark.parametrize("name", ["fourbar", "boom-cylinder",
                                  pytest.param("pump", marks=pytest.mark.slow),
                                  pytest.param("garage-door", marks=pytest.mark.slow)])
def test_the_quick_reading_agrees_with_jsonschema_on_damaged_templates(name):
    validator = jsonschema.Draft7Validator(schema.schema())
    judged = sure = refused = 0
    for doc in _share(_damaged(_bundled()[name]), seed=name):
        judged += 1
        quick = schema.fits(doc)
        if quick is not None:
            assert quick == validator.is_valid(doc), doc
            sure += 1
            refused += not quick
    # the reading is sure of nearly all of them (else it would save little), and they include
    # many a template jsonschema refuses
    assert sure > 0.9 * judged
    assert refused > 100 * SHARE


@pytest.mark.parametrize("value, part, expected", [
    (True, {"type": "integer"}, False),         # bool is an int in Python, not in JSON
    (True, {"type": "number"}, False),
    (1, {"const": True}, False),
    (True, {"enum": [1, 2]}, False),
    (1.0, {"const": 1}, True),
    ([1, True], {"const": [1, 1]}, False),
    ({"a": [0.0]}, {"const": {"a": [0]}}, True),
    ("ab\n", {"pattern": "^[a-z]+$"}, True),    # re.search, as jsonschema reads a pattern
    (5, {"pattern": "^x$", "exclusiveMinimum": 5}, False),
    ([1], {"items": {"type": "string"}, "minItems": 1}, False),
    ({"a": 1}, {"propertyNames": {"pattern": "^[A-Z]"}}, False),
    ({"b": 1}, {"properties": {"a": {}}, "additionalProperties": False}, False),
    ({"t": "x"}, {"if": {"properties": {"t": {"const": "x"}}}, "then": {"required": ["u"]},
                  "else": {"required": ["v"]}}, False),
    ({"t": "y", "v": 0}, {"if": {"properties": {"t": {"const": "x"}}},
                          "then": {"required": ["u"]}, "else": {"required": ["v"]}}, True),
    ({"t": "y"}, {"if": {"properties": {"t": {"const": "x"}}}, "then": {"required": ["u"]},
                  "else": {"required": ["v"]}}, False),
    (2, {"oneOf": [{"type": "integer"}, {"type": "number"}]}, False),
    (2.5, {"oneOf": [{"type": "string"}, {"type": "number"}]}, True),
])
def test_the_quick_reading_of_one_keyword_is_jsonschemas(value, part, expected):
    assert jsonschema.Draft7Validator(part).is_valid(value) is expected
    assert schema._fits(value, part) is expected


@pytest.mark.parametrize("value, part", [
    (3.0, {"type": "integer"}),                 # a whole number in Draft 7
    ((1, 2), {"type": "array"}),                # no JSON value: not read quickly
    ({"a": 1}, {"patternProperties": {"^a$": {}}, "additionalProperties": False}),
    ([1], {"items": [{"type": "integer"}]}),
    (1, {"$ref": "#/definitions/x"}),
])
def test_the_quick_reading_leaves_what_it_does_not_know_to_jsonschema(value, part):
    with pytest.raises(schema._Unsure):
        schema._fits(value, part)
