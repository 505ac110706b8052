"""What reading any of a book's cells shares: the refusal of a file that cannot be judged at
all, and a cell that must hold a number (reading.py and synthesis.py read with them)."""
from __future__ import annotations


class UnusableFile(Exception):
    """The file cannot be verified at all (exit 2)."""


def number_at(ws, cell: str, what: str) -> float:
    v = ws[cell].value
    if not isinstance(v, (int, float)) or isinstance(v, bool):
        raise UnusableFile(f"{ws.title}!{cell}: {what} must be a number (got {v!r})")
    return float(v)
