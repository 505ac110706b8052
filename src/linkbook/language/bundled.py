"""The bundled templates' folder and the mechanism a workbook's build record describes.

Verify compiles the description a book records; it reads no template file (but an older book's,
whose record names a bundled mechanism only) and needs none of templates.py's checks.
"""
from __future__ import annotations

from pathlib import Path

from ..base.record import BuildRecord
from .compiler import DescriptionError, compile_mechanism
from .mechanisms import Mechanism


def _template_dir() -> Path:
    """Installed: templates/ is packaged inside linkbook; from a checkout: the repo's templates/."""
    package = Path(__file__).resolve().parents[1]
    packaged = package / "templates"
    return packaged if packaged.is_dir() else package.parents[1] / "templates"


TEMPLATE_DIR = _template_dir()


def bundled() -> list[Path]:
    return sorted(TEMPLATE_DIR.glob("*.toml"))


def bundled_template_data(name: str) -> dict | None:
    """The TOML data of the bundled template `name`, if it describes a mechanism."""
    import tomllib
    path = TEMPLATE_DIR / f"{name}.toml"
    if not path.is_file():
        return None
    data = tomllib.loads(path.read_text(encoding="utf-8"))
    return data if isinstance(data.get("mechanism"), dict) else None


def from_record(record: BuildRecord) -> Mechanism:
    """The mechanism a workbook's build record describes (verify reads an edited book back). A
    book written before the mechanism language records only a bundled mechanism's name: its
    description is that template's (the one older record the record's upgrade cannot fill in
    from the record alone)."""
    grid = (record.grid.param, record.grid.key) if record.grid is not None else None
    description = record.description
    if description is None:
        data = bundled_template_data(record.mechanism)
        if data is None:
            raise DescriptionError("workbook", f"unknown mechanism {record.mechanism!r}")
        description = data["mechanism"]
    return compile_mechanism(record.mechanism, description, record.kinds(), "workbook", grid)
