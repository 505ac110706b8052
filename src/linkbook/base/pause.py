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
"""
from __future__ import annotations

import functools
import gc


def gc_paused(func):
    @functools.wraps(func)
    def paused(*args, **kwargs):
        if not gc.isenabled():
            return func(*args, **kwargs)
        gc.disable()
        try:
            return func(*args, **kwargs)
        finally:
            gc.enable()
    return paused
