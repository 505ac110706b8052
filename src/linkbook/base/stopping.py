"""Ctrl-C and SIGTERM while a command runs: each raises where the process is, so that what is
half-done is undone on the way out, and each is also recorded, so that it cannot be lost.

Python runs a signal's handler between two steps of whatever code is running, and that can be a
`__del__`, a weakref callback or a library's `except BaseException`: there the handler's
exception is swallowed (Python prints "Exception ignored ...") and the command would go on to
write its file and exit 0. The record survives: `stop_if_signalled()` raises the stop again at
the next safe point (before a file is renamed into place, when the command returns).
"""
from __future__ import annotations

import contextlib
import signal
import sys


class Terminated(BaseException):
    """SIGTERM, raised as Ctrl-C raises KeyboardInterrupt. A BaseException, as KeyboardInterrupt
    is: no `except Exception` may swallow it."""


# signal -> (the exception it raises, its name in the one line, the exit status 128 + signum)
STOPS = {signal.SIGINT: (KeyboardInterrupt, "Ctrl-C (SIGINT)", 128 + signal.SIGINT),
         signal.SIGTERM: (Terminated, "SIGTERM", 128 + signal.SIGTERM)}

_received: list[int] = []       # the signals that arrived while the handlers were ours


def stop_of(exc: BaseException) -> tuple[str, int] | None:
    """(the signal's name, the exit status) for an exception a stop raised; None otherwise."""
    for kind, name, status in STOPS.values():
        if isinstance(exc, kind):
            return name, status
    return None


def stop_if_signalled() -> None:
    """Raise the stop the first signal asked for, if one arrived (its own raise may have been
    swallowed where it landed, or it may be held back pending)."""
    signum = _first_signal()
    if signum is not None:
        raise STOPS[signum][0]()


def _handle(signum, frame):
    _received.append(signum)
    raise STOPS[signum][0]()


def _unraisable_hook(before):
    """Python's report of an exception it had to drop: silent for a stop (it is recorded and
    raised again), as before for anything else."""
    def hook(unraisable):
        if stop_of(unraisable.exc_value) is None:
            before(unraisable)
    return hook


class handled:
    """Within this, SIGINT and SIGTERM raise and are recorded (in the main thread only, where
    Python runs signal handlers); the handlers before it are put back afterwards. Within an
    outer one (the entry point's, around main()'s), it leaves the outer one's in place."""

    def __enter__(self):
        import threading
        self.before = {}
        if (threading.current_thread() is not threading.main_thread()
                or signal.getsignal(signal.SIGTERM) is _handle):
            return self
        _received.clear()
        self.hook = sys.unraisablehook
        sys.unraisablehook = _unraisable_hook(self.hook)
        for signum in STOPS:
            self.before[signum] = signal.signal(signum, _handle)
        return self

    def __exit__(self, *exc) -> None:
        if not self.before:
            return
        for signum, handler in self.before.items():
            signal.signal(signum, handler)
        sys.unraisablehook = self.hook
        _received.clear()           # the command is over: a later write is not stopped by it


@contextlib.contextmanager
def held():
    """Hold SIGINT and SIGTERM back (pending) within this: for a step that must not be cut in
    two, or after which the process ends and `arrived()` looks at them once."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    before = signal.pthread_sigmask(signal.SIG_BLOCK, set(STOPS))
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def arrived() -> tuple[str, int] | None:
    """(the name, the exit status) of a signal that arrived: recorded, or held back pending."""
    signum = _first_signal()
    return None if signum is None else STOPS[signum][1:]


def _first_signal() -> int | None:
    if _received:
        return _received[0]
    pending = signal.sigpending() & set(STOPS) if hasattr(signal, "sigpending") else set()
    return min(pending, default=None)
