"""The drawing's colours, its links' names and its grid step: shared by the book's charts and by
`linkbook animate`, so that a GIF looks like the book it was made from."""
from __future__ import annotations

import math

LINK_COLOURS = ("4F81BD", "C0504D", "9BBB59", "F79646", "4BACC6", "1F497D", "948A54")
PATH_COLOUR = "8064A2"
GROUND_COLOUR = "7F7F7F"
# a slider's guide: a thin grey line; its block: a dark outline (neither takes a link's colour)
PART_COLOURS = {"guide": GROUND_COLOUR, "slot": GROUND_COLOUR, "block": "404040"}


def drawing_colours(drawing: list[dict]) -> list[str]:
    """A colour per drawn link: grey for the ground, the palette in turn for moving links."""
    colours, k = [], 0
    for link in drawing:
        if link.get("ground"):
            colours.append(GROUND_COLOUR)
        elif link.get("kind") in PART_COLOURS:
            colours.append(PART_COLOURS[link["kind"]])
        else:
            colours.append(LINK_COLOURS[k % len(LINK_COLOURS)])
            k += 1
    return colours


def link_label(link: dict, i: int) -> str:
    """The legend's name of a drawn link (books built before labels: numbered from 1)."""
    if "label" in link:
        return link["label"]
    joints = link["joints"]
    body = joints[:-1] if len(joints) > 2 and joints[0] == joints[-1] else joints
    return f"link {i}: {''.join(body)}"


def nice_step(span: float) -> float:
    """A 1-2-5 grid step giving about 6 divisions."""
    raw = span / 6
    power = 10 ** math.floor(math.log10(raw))
    return next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw)
