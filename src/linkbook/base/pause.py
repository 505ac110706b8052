"""Python's cyclic garbage collector paused while a book is built or verified.

A build or a verify makes hundreds of thousands of objects that live until it ends (cells,
formula texts, compiled formulas, value grids), and every few hundred allocations the collector
walks the young ones, every few of those walks the older ones as well: a large share of a big
book's build and verify went to finding cycles that are not there (the README gives the figures).
Reference counting frees memory as usual meanwhile (the peak is the same); cycles made during
the call are collected once the collector resumes. The collector is a process-wide switch: it is
left off if it was off, and back on when the call returns or raises. It is paused per book, not
for a whole command: `build --all` or a verify of many books collects between them (paused
across them, garbage cycles would add up book after book).

The command line's process ends (os._exit) when its command does: there it stays off from the
start (pause_until_exit), through the imports, and each book after the first begins by
collecting what the one before it left; after the last book nothing is collected, as nothing
would be freed that the exit does not free. Resuming it after the book had cost a bundled
book's verify more than any of its checks.
"""
from __future__ import annotations

import functools
import gc

_until_exit = False     # pause_until_exit() was called: the process ends with its command
_begun = 0              # paused calls begun under it
_running = 0            # paused calls running (one may call another)


def pause_until_exit() -> None:
    """The collector off until the process ends; each paused call after the first collects
    the garbage cycles of those before it (the command line's process shell calls this)."""
    global _until_exit
    _until_exit = True
    gc.disable()


def gc_paused(func):
    @functools.wraps(func)
    def paused(*args, **kwargs):
        if _until_exit:
            return _paused_until_exit(func, args, kwargs)
        if not gc.isenabled():
            return func(*args, **kwargs)
        gc.disable()
        try:
            return func(*args, **kwargs)
        finally:
            gc.enable()
    return paused


def _paused_until_exit(func, args, kwargs):
    global _begun, _running
    if _begun and not _running:
        gc.collect()        # the books before this one: their cycles, at once
    _begun += 1
    _running += 1
    try:
        return func(*args, **kwargs)
    finally:
        _running -= 1
