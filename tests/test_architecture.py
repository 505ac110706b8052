"""The house's rules, read from the code's own imports (every import, also those inside functions).

The package is six wings, each a subpackage of src/linkbook (README, "Architecture"):
base (what all share) < language (TOML -> symbolic model) and engine (evaluating a book)
< book (the writer) and check (the independent reference and the judge) < apps (command line,
animate, info, export, preview) < the package's face (linkbook/__init__.py, __main__.py).
A module imports only from its own wing and the wings below it, the imports make no circle, the
independent reference takes nothing from the writer or the language (else it would check the
writer against itself), the readers of books take the record, not the writer, and the writer
never needs the LibreOffice runner.
"""
from __future__ import annotations

import ast
import graphlib
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "linkbook"
RANK = {"base": 0, "language": 1, "engine": 1, "book": 2, "check": 2, "apps": 3, "": 4}
# Wings of one rank that must not import each other either. The writer may ask the independent
# reference (which curves of a chart coincide, for the legend); the check never reads the writer.
APART = {("language", "engine"), ("engine", "language"), ("check", "book")}
MAX_MODULE_LINES = 1_000
MAX_CLASS_LINES = 300


def module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _absolute(node: ast.ImportFrom, here: str, is_package: bool) -> str:
    if node.level == 0:
        return node.module or ""
    base = here.split(".") if is_package else here.split(".")[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """The project's modules that `name` imports, anywhere in its text."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names if a.name.startswith("linkbook")}
        elif isinstance(node, ast.ImportFrom):
            target = _absolute(node, name, path.name == "__init__.py")
            if not target.startswith("linkbook"):
                continue
            # `from linkbook.book import builder` names a module; `from .x import f` a function
            subs = {f"{target}.{a.name}" for a in node.names} & known
            found |= subs or {target}
    return {m for m in found if m != name}


def graph() -> dict[str, set[str]]:
    mods = modules()
    return {name: imports_of(name, path, set(mods)) & set(mods) for name, path in mods.items()}


FACE = {"linkbook", "linkbook.__main__"}


def wing(module: str) -> str:
    """The wing a module belongs to ("" for the package's face); a module outside every wing is
    refused, so that a stray top-level module cannot escape the rules."""
    if module in FACE:
        return ""
    parts = module.split(".")
    if len(parts) < 2 or parts[1] not in RANK or parts[1] == "":
        raise ValueError(f"{module} is in no wing")
    return parts[1]


def reach(edges: dict[str, set[str]], start: str) -> set[str]:
    """Every module that `start` and the modules under it import, directly or not."""
    todo = [m for m in edges if m == start or m.startswith(start + ".")]
    seen = set(todo)
    while todo:
        for t in edges.get(todo.pop(), ()):
            if t not in seen:
                seen.add(t)
                todo.append(t)
    return seen


def wrong_way(edges: dict[str, set[str]]) -> list[str]:
    """Imports of a higher wing, or of a wing of the same rank kept apart."""
    return sorted(f"{m} -> {t}" for m, ts in edges.items() for t in ts
                  if RANK[wing(t)] > RANK[wing(m)] or (wing(m), wing(t)) in APART)


def circle(edges: dict[str, set[str]]) -> list[str]:
    """One loop of imports (its modules in order), or [] when there is none."""
    try:
        graphlib.TopologicalSorter(edges).prepare()
    except graphlib.CycleError as loop:
        return loop.args[1]
    return []


def _ignoring_package_faces(edges):
    """A package's face (__init__) re-exporting its own modules is not an import of the wing by
    itself; an import of the face is an import of the wing."""
    return {m: {t for t in ts if not m.startswith(t + ".")} for m, ts in edges.items()}


def test_the_reader_sees_every_module_and_its_imports():
    """The rules below are only as good as this reading: it must see the wings and the imports
    the code makes at module level and inside functions."""
    edges = graph()
    assert {wing(m) for m in edges} == set(RANK)
    assert "linkbook.base.xlsx" in edges["linkbook.engine.grammar"]
    # builder imports page setup inside a function; verify's report imports verify's module
    # inside one
    assert "linkbook.book.pages" in edges["linkbook.book.builder"]
    assert any(m.startswith("linkbook.check") for m in edges["linkbook.apps.verdict"])


def test_no_import_circles():
    found = circle(_ignoring_package_faces(graph()))
    assert not found, "modules that import each other in a loop: " + " -> ".join(found)


def test_no_wing_imports_a_higher_wing_or_its_neighbour():
    bad = wrong_way(graph())
    assert not bad, "imports against the wings' order:\n" + "\n".join(bad)


INDEPENDENT = ("linkbook.book", "linkbook.language", "linkbook.engine")


@pytest.mark.parametrize("reader, forbidden", [
    ("linkbook.check.reference", INDEPENDENT),
    ("linkbook.check.forces", INDEPENDENT),
    ("linkbook.check", ("linkbook.book",)),
    ("linkbook.apps.animate", ("linkbook.book",)),
    ("linkbook.book", ("linkbook.engine.office",)),
])
def test_who_may_not_reach_whom(reader, forbidden):
    """Through any chain of imports, not only directly."""
    bad = sorted(t for t in reach(graph(), reader)
                 if any(t == f or t.startswith(f + ".") for f in forbidden))
    assert not bad, f"{reader} reaches " + ", ".join(bad)


def test_export_reads_a_book_without_the_writer():
    """export imports nothing of the writer itself; it takes the Book that info reads (info
    may also build a template in memory for `linkbook info NAME`: that is info's, not
    export's)."""
    edges = graph()
    bad = sorted(t for m, ts in edges.items() if m == "linkbook.apps.export"
                 for t in ts if t.startswith("linkbook.book"))
    assert not bad, ", ".join(bad)


def test_the_rules_catch_a_circle_and_a_wrong_way_import():
    """The checks fail on a house that breaks them (so a passing run means something)."""
    edges = graph()
    edges["linkbook.base.xlsx"] = edges["linkbook.base.xlsx"] | {"linkbook.book.workbook"}
    assert circle(_ignoring_package_faces(edges))
    assert wrong_way(edges) == ["linkbook.base.xlsx -> linkbook.book.workbook"]
    edges = graph()
    edges["linkbook.check.judge"] = edges["linkbook.check.judge"] | {"linkbook.book.style"}
    assert wrong_way(edges) == ["linkbook.check.judge -> linkbook.book.style"]
    assert "linkbook.engine.office" in reach(
        {**edges, "linkbook.book.style": edges["linkbook.book.style"] | {"linkbook.check.judge"}},
        "linkbook.book")
    with pytest.raises(ValueError):
        wing("linkbook.util")


def test_relative_imports_resolve_as_python_resolves_them():
    tree = ast.parse("from ..x import y\nfrom . import z\ndef f():\n    from .w import v\n")
    first, second, inner = [n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    assert _absolute(first, "linkbook.book", is_package=True) == "linkbook.x"
    assert _absolute(first, "linkbook.book.style", is_package=False) == "linkbook.x"
    assert _absolute(second, "linkbook.book.style", is_package=False) == "linkbook.book"
    assert _absolute(inner, "linkbook.check.reference", is_package=True) == \
        "linkbook.check.reference.w"


def test_modules_and_classes_stay_small():
    too_long = []
    for name, path in modules().items():
        text = path.read_text(encoding="utf-8")
        lines = len(text.splitlines())
        if lines > MAX_MODULE_LINES:
            too_long.append(f"{name}: {lines} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.ClassDef) and node.end_lineno - node.lineno + 1 > MAX_CLASS_LINES:
                too_long.append(f"{name}.{node.name}: {node.end_lineno - node.lineno + 1} lines")
    assert not too_long, "\n".join(too_long)
