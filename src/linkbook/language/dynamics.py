"""The force analysis' keys of a description (docs/language.md, "Mass, gravity and loads"):
`dynamics`, `bodies` and `loads`, checked where the schema cannot check them.

The schema has checked their shape already; here each name must be one the mechanism has (a
link's joints its points, a centre's frame two of those joints, a load's point a point) and each
value an expression of what an `expression` step may use, the Motion sheet's rates (a damper's
−c·ω) and `to_metres` (metres per length unit: a load may convert a length with it). Nothing is
written into the model: a book built from a description with these keys is the book built
without them.
"""
from __future__ import annotations

from ..base.errors import InputError
from .bodies import METRES
from .domain import check_value
from .expressions import expression, is_comparison
from .mechanisms import ANGLE_KIND, BRANCH_KIND
from .steps import STEPS
from .steps.step_type import slotted
from .model import DescriptionError
from .schema import mechanism_key_problem

KEYS = ("dynamics", "bodies", "loads")

# The ways a centre of mass is placed, as a point step places a point, each with the key that
# may go with it
_CENTRE_FORMS = {"local": set(), "distances": {"side"}, "distance": {"angle"}}


def check_dynamics(c, data: dict, steps_keys: set[str]) -> None:
    """Check the description's dynamics, bodies and loads against the compiled steps of `c`
    (a Compiler that has placed every step); `steps_keys`: the keys of the quantities the steps
    placed, which their expressions may name as an `expression` step's formula does, and the
    Motion sheet's rates (a mass, an inertia and a load may read them; a centre and gravity
    only the parameters)."""
    for key in KEYS:
        found = mechanism_key_problem(key, data[key]) if key in data else None
        if found:
            raise DescriptionError(f"{c.origin}: {found[0]}", found[1])
    # what an expression step may name, less the compiler's own aliases (their keys start with _)
    known = {k for k in c.symbols | c.swept | steps_keys if not k.startswith("_")} | {METRES}
    constant = set(c.symbols) | {METRES}   # a centre's place and gravity: the parameters alone
    field = c.field
    gravity = (data.get("dynamics") or {}).get("gravity")
    if gravity is not None:
        for k in ("g", "angle"):
            if k in gravity:
                _value(c, f"{field}.dynamics.gravity.{k}", gravity[k], constant,
                       "acceleration" if k == "g" else ANGLE_KIND)
    for i, body in enumerate(data.get("bodies") or []):
        _check_body(c, f"{field}.bodies[{i}]", body, known)
    for i, load in enumerate(data.get("loads") or []):
        _check_load(c, f"{field}.loads[{i}]", load, known)


def _point(c, field: str, name: str) -> str:
    if name not in c.points:
        raise DescriptionError(field, f"{name!r} is no point of the mechanism; its points: "
                                      f"{', '.join(c.points)}")
    return name


def _points(c, field: str, names: list) -> list[str]:
    """Each name a point of the mechanism, none twice."""
    for i, name in enumerate(names):
        _point(c, f"{field}[{i}]", name)
        if name in names[:i]:
            raise DescriptionError(f"{field}[{i}]", f"{name!r} is named twice")
    return list(names)


def _block_points(c) -> set[str]:
    """The points blocks slide with (a slider's and a slot's point, a slide's p, the pin in a
    vector step's slotted link), as the steps' topologies say."""
    made = slotted([(rec, STEPS[rec["type"]].topology(rec, None)) for rec in c.records])
    return {m.block.point for _, m in made if m.block is not None}


def _check_body(c, field: str, body: dict, known: set[str]) -> None:
    joints = _points(c, f"{field}.joints", body["joints"])
    if body.get("block", False):
        if len(joints) != 1 or joints[0] not in _block_points(c):
            raise DescriptionError(f"{field}.joints", "a block is named by its one point, a "
                                                      "slider's or a slot's point, a slide's p "
                                                      "or the pin in a slotted link (got "
                                                      f"{joints!r})")
        if "centre" in body:
            raise DescriptionError(f"{field}.centre", "a block's centre of mass is its point")
    else:
        if len(joints) < 2:
            raise DescriptionError(f"{field}.joints", "a link is named by two of its points or "
                                                      f"more (a block: block = true) "
                                                      f"(got {joints!r})")
        if "mass" in body and "centre" not in body:
            raise DescriptionError(f"{field}.centre", "is missing: a link's mass needs its "
                                                      "centre")
    for k in ("mass", "inertia"):
        if k in body:
            _value(c, f"{field}.{k}", body[k], known, k)
    if "centre" in body:
        _check_centre(c, f"{field}.centre", body["centre"], joints, set(c.symbols) | {METRES})


def _check_centre(c, field: str, centre: dict, joints: list[str], known: set[str]) -> None:
    frame = centre["frame"]
    if len(set(frame)) != 2 or not set(frame) <= set(joints):
        raise DescriptionError(f"{field}.frame", f"must be two different joints of the link "
                                                 f"{joints} (got {frame!r})")
    forms = [k for k in _CENTRE_FORMS if k in centre]
    if len(forms) != 1:
        raise DescriptionError(field, "needs exactly one of local, distances or distance "
                                      f"(got {', '.join(forms) or 'none'})")
    for k in ("side", "angle"):
        if k in centre and k not in _CENTRE_FORMS[forms[0]]:
            raise DescriptionError(f"{field}.{k}", f"does not go with {forms[0]}")
    values = centre[forms[0]]
    for i, value in enumerate(values if isinstance(values, list) else [values]):
        expression(f"{field}.{forms[0]}" + (f"[{i}]" if isinstance(values, list) else ""),
                   value, known)
    if "angle" in centre:
        _value(c, f"{field}.angle", centre["angle"], known, ANGLE_KIND)
    side = centre.get("side", 1)
    if isinstance(side, str) and c.kinds.get(side) != BRANCH_KIND:
        raise DescriptionError(f"{field}.side", f"must be 1, -1 or a branch parameter "
                                                f"(got {side!r})")


def _check_load(c, field: str, load: dict, known: set[str]) -> None:
    if "at" in load:
        _point(c, f"{field}.at", load["at"])
    if "body" in load:
        joints = _points(c, f"{field}.body", load["body"])
        if "at" in load and load["at"] not in joints:
            raise DescriptionError(f"{field}.body", f"must hold the point {load['at']!r} the "
                                                    f"force acts at (got {joints!r})")
    force = load.get("force")
    if isinstance(force, list):
        for i, value in enumerate(force):
            _value(c, f"{field}.force[{i}]", value, known, "force")
    elif isinstance(force, dict):
        for k in ("magnitude", "angle"):
            if k in force:
                _value(c, f"{field}.force.{k}", force[k], known, "force" if k == "magnitude"
                       else ANGLE_KIND)
    if "torque" in load:
        _value(c, f"{field}.torque", load["torque"], known, "torque")


def _value(c, field: str, raw: object, known: set[str], kind: str) -> None:
    """An expression of what `known` names, a number and not TRUE or FALSE; a number written as
    it is in the domain of its kind, as a parameter's value is (domain.check_value: a load near
    the least double is refused, an angle beyond ±360°). Kept in `c.loads`: with the template's
    values none may be an error on every row (templates.check_loads)."""
    expression(field, raw, known)
    if is_comparison(raw):
        raise DescriptionError(field, f"{raw!r} is a comparison, TRUE or FALSE: a load must be "
                                      "a number (IF(c, a, b) chooses one)")
    c.loads.append((field, raw))
    if isinstance(raw, (int, float)) and not isinstance(raw, bool):
        try:
            check_value(field, kind, raw)
        except InputError as exc:
            raise DescriptionError(field, exc.message) from None
