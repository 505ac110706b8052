"""The typed build record: it gives back exactly the JSON the writer records, an older book's
record is read in today's shape, and a key the record does not know fails at build."""
from __future__ import annotations

import json
from dataclasses import MISSING, FrozenInstanceError, field, fields, make_dataclass, replace

import openpyxl
import pytest

from conftest import built

from linkbook.base import record as record_module
from linkbook.base import sheets
from linkbook.base.record import BuildRecord, DamagedRecord, upgrade


def _text(data) -> str:
    return json.dumps(data, ensure_ascii=False, sort_keys=True)


@pytest.mark.parametrize("name", ["fourbar", "pump", "boom-cylinder", "jansen"])
def test_the_record_gives_back_the_json_the_writer_assembled(name):
    b, _ = built(name)
    assert _text(BuildRecord.from_json(b.meta).to_json()) == _text(b.meta)
    assert b.record == BuildRecord.from_json(b.meta)


def test_the_record_is_read_typed_from_the_sheet():
    b, _ = built("pump")
    record = sheets.read_record(b.workbook)
    assert record == b.record
    assert record.sweep.cells("s15")[0] == f"{b.meta['sweep']['columns']['s15']}5"
    assert record.grid.stroke_step == b.meta["grid"]["stroke_step"]
    assert record.motion.current_row == b.meta["motion"]["current_row"]


def test_a_key_the_record_does_not_know_fails_when_written():
    b, _ = built("fourbar")
    wrong = {**b.meta, "sweep": {**b.meta["sweep"], "colums": {}}}
    ws = openpyxl.Workbook().active
    with pytest.raises(KeyError, match="colums"):
        sheets.write_meta(ws, wrong)


def test_a_value_of_the_wrong_type_is_refused():
    b, _ = built("fourbar")
    with pytest.raises(TypeError):
        BuildRecord.from_json({**b.meta, "sweep": 7})
    with pytest.raises(ValueError):
        BuildRecord.from_json({**b.meta, "sweep": {**b.meta["sweep"], "rows": [5]}})


@pytest.mark.parametrize("data", [None, [1, 2], "x", {"format": 2}, {"format": "1"}])
def test_no_record_of_this_format_is_damaged(data):
    with pytest.raises(DamagedRecord):
        BuildRecord.from_json(data)


def test_an_older_record_is_read_in_todays_shape():
    """The entries older books lack: filled as those books were laid out."""
    b, _ = built("fourbar")
    old = json.loads(json.dumps(b.meta))
    for key in ("constants", "summary", "numbers_only", "controls", "length_unit", "frames"):
        del old[key]
    del old["sweep"]["sheet"]
    for link in old["position"]["drawing"]:
        del link["label"]
    record = BuildRecord.from_json(old)
    assert (record.constants, record.summary, record.numbers_only, record.controls) == (
        {}, {}, (), {})
    assert record.length_unit == "mm" and record.sweep.sheet == "Sweep"
    assert record.frames is None
    assert record.position.drawing[0].label.startswith("link 1: ")
    assert upgrade(b.meta) == b.meta        # today's shape comes back equal


# ---------------------------------------------------------------- a part is a frozen dataclass
def _parts() -> list[type]:
    return [cls for cls in vars(record_module).values()
            if isinstance(cls, type) and issubclass(cls, record_module.Part)
            and cls is not record_module.Part]


def _twin(cls: type) -> type:
    """The standard library's frozen dataclass of the same name and fields."""
    specs = [(f.name, f.type) if f.default is MISSING else
             (f.name, f.type, field(default=f.default)) for f in fields(cls)]
    return make_dataclass(cls.__name__, specs, frozen=True)


def _arguments(cls: type, seed: int) -> list:
    """A value for each field (hashable, so that the hash can be compared too)."""
    return [f"{f.name}{seed}" if seed % 2 else seed + i for i, f in enumerate(fields(cls))]


@pytest.mark.parametrize("cls", _parts(), ids=lambda cls: cls.__name__)
def test_a_part_behaves_as_the_frozen_dataclass_of_its_fields(cls):
    twin = _twin(cls)
    required = [f for f in fields(cls) if f.default is MISSING]
    for seed in (1, 2):
        args = _arguments(cls, seed)
        named = dict(zip([f.name for f in fields(cls)], args))
        ours, theirs = cls(*args), twin(*args)
        assert repr(ours) == repr(theirs)
        assert hash(ours) == hash(theirs)
        assert ours == cls(**named) and not ours != cls(**named)
        assert ours != cls(*_arguments(cls, seed + 2))
        assert (ours == theirs) is False            # another class, as between dataclasses
        assert (ours == type("Sub", (cls,), {})(*args)) is False
        assert (theirs == type("Sub", (twin,), {})(*args)) is False
        assert replace(ours, **{fields(cls)[0].name: "changed"}) == \
            cls(*(["changed"] + args[1:]))
        short = cls(*args[:len(required)])           # the defaulted fields left out
        assert short == cls(**{k: named[k] for k in list(named)[:len(required)]})
        assert repr(short) == repr(twin(*args[:len(required)]))
        with pytest.raises(FrozenInstanceError):
            setattr(ours, fields(cls)[0].name, 0)
        with pytest.raises(FrozenInstanceError):
            delattr(ours, fields(cls)[0].name)
        with pytest.raises(FrozenInstanceError):
            ours.new_attribute = 0
    for bad_args, bad_kwargs in (((), {}) if required else ((0,) * 99, {}),
                                 ((0,) * (len(fields(cls)) + 1), {}),
                                 ((), {"no_such_field": 0}),
                                 ((0,), {fields(cls)[0].name: 0})):
        for make in (cls, twin):
            with pytest.raises(TypeError):
                make(*bad_args, **bad_kwargs)


def test_an_older_record_names_a_bundled_mechanism_and_verify_compiles_its_description():
    """A book written before the mechanism language records no description: verify takes the
    bundled template's (language/bundled.py), read from the template file itself here."""
    import tomllib

    from linkbook.language.bundled import TEMPLATE_DIR, from_record
    from linkbook.language.model import DescriptionError
    b, _ = built("fourbar")
    meta = {k: v for k, v in b.meta.items() if k != "description"}
    mechanism = from_record(BuildRecord.from_json(meta))
    toml = tomllib.loads((TEMPLATE_DIR / "fourbar.toml").read_text(encoding="utf-8"))
    assert mechanism.description == toml["mechanism"]
    assert mechanism.parameters == b.record.kinds()
    with pytest.raises(DescriptionError, match="unknown mechanism 'fivebar'"):
        from_record(BuildRecord.from_json({**meta, "mechanism": "fivebar"}))
