"""A fresh clone alone passes its tests: nothing in the repository reads a path outside it.

The published acceptance numbers live in tests/data/published.toml (each entry names its source);
no source, test, benchmark or docs script may reach for a folder beside the repository."""
from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# A path that climbs out of the repository: a parent of the repository's root, a "../" literal, or
# the reference folder that sits beside the repository on the developers' machines.
OUTSIDE = re.compile(r"""(?:ROOT|REPO|HERE|repo_root)\.parent\b|["']\.\./|\bshared/(?:reference|seeds)\b|parents\[(?:[3-9])\]""")


def python_files() -> list[Path]:
    listed = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "*.py"],
                            cwd=ROOT, capture_output=True, text=True)
    if listed.returncode == 0 and listed.stdout.strip():
        return [ROOT / line for line in listed.stdout.splitlines() if (ROOT / line).is_file()]
    return [p for part in ("src", "tests", "benchmarks", "docs") for p in (ROOT / part).rglob("*.py")]


def test_nothing_reads_outside_the_repository():
    this = Path(__file__).resolve()
    found = [f"{path.relative_to(ROOT)}:{n}: {line.strip()}"
             for path in python_files() if path.resolve() != this
             for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
             if OUTSIDE.search(line)]
    assert not found, "\n".join(found)


@pytest.mark.parametrize("line", [
    'for base in (ROOT.parent / "shared", ROOT / "shared"):',
    # (written in pieces, so that a search of the sources for such a path does not find this test)
    "path = Path(" + repr(".." + "/shared" + "/reference/published.toml") + ")",
    'data = REPO.parent / "x"',
])
def test_the_check_sees_a_path_outside(line):
    assert OUTSIDE.search(line)


def test_published_numbers_are_inside():
    text = (ROOT / "tests" / "data" / "published.toml").read_text(encoding="utf-8")
    assert "[pump_table_example_4]" in text and "source =" in text
