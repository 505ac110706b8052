"""Whole-process timings should see linkbook as an installed package does: pip compiles a
package's modules to bytecode when it installs it.  A source checkout in an environment with
PYTHONDONTWRITEBYTECODE set (as this machine's) would otherwise compile every module of linkbook
again in every process, about 0.1 s that no user pays."""
from __future__ import annotations

import compileall
from pathlib import Path


def compile_tree(src: Path) -> None:
    """Write the bytecode of every module under `src` (a tree's src/), as `pip install` does."""
    if not compileall.compile_dir(str(src), quiet=1):
        raise SystemExit(f"cannot compile the sources under {src}")
