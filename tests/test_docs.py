"""The front door (issue 40): a README that starts people, details in docs/, and no link that
leads nowhere."""
from __future__ import annotations

import re
from pathlib import Path

from conftest import ROOT

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
LINK = re.compile(r"\]\(([^)\s]+)\)")


def _anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    return {_anchor(m[1]) for m in re.finditer(r"^#+ (.*)$", page.read_text(encoding="utf-8"),
                                                re.M)}


def test_the_readme_is_a_front_door():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.encode("utf-8")) <= 15_000
    first = text.splitlines()[:60]
    assert "pip install . && linkbook build --all" in first
    assert "pip install '.[test]' && python -m pytest" in first


def test_every_link_resolves():
    broken = []
    for page in PAGES:
        for target in LINK.findall(page.read_text(encoding="utf-8")):
            if target.startswith(("http://", "https://", "mailto:")):
                continue
            path, _, anchor = target.partition("#")
            where = (page.parent / path) if path else page
            if not where.exists():
                broken.append(f"{page.name}: {target}")
            elif anchor and where.suffix == ".md" and anchor not in _anchors(where):
                broken.append(f"{page.name}: {target} (no such heading)")
    assert not broken, broken


def test_the_anchor_rule_is_githubs():
    assert _anchor("Animations (`linkbook animate`)") == "animations-linkbook-animate"
    assert _anchor("What the language cannot express") == "what-the-language-cannot-express"
