"""What a command says on stderr besides its output: one line each, never a traceback."""
from __future__ import annotations

import sys


def error(exc: Exception) -> None:
    """The one line a failure ends with, on stderr: whole (it names the field and the value),
    its line breaks, if any, joined."""
    print(f"linkbook: error: {' '.join(str(exc).split())}", file=sys.stderr)


def notes(path, found) -> None:
    """What a book holds that leaves its numbers alone, one warning line each on stderr."""
    for note in found:
        print(f"linkbook: warning: {path}: {note}", file=sys.stderr)


def warn(built) -> None:
    """What the user should know about a book that is not an error (a loop that cannot close
    over part of the sweep): one line each on stderr."""
    for line in built.warnings:
        print(f"linkbook: warning: {line}", file=sys.stderr)
