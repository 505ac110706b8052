"""The `linkbook` command's process: the signals taken first, the arguments parsed
(arguments.py), the command run (COMMANDS: commands.py, verdict.py), every failure ended in one
line and the process ended at once."""
from __future__ import annotations

import os
import sys

# One BLAS thread for the command. OpenBLAS starts a thread per core when numpy is first imported,
# which cost 0.07-0.12 s of CPU on every command here (2 cores), and nothing linkbook computes
# is a matrix product big enough to share out. Set before anything imports numpy; a user's own
# setting wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

# Nothing heavy at the top: what the module imports runs before main() has the signals in hand
# (a Ctrl-C there ends in Python's traceback); each function imports what it needs.
from ..base import stopping  # noqa: E402 (after the setting above)
from ..base.errors import InputError  # noqa: E402


# command -> (the module of linkbook.apps that runs it, its function), imported only when that
# command runs: a command loads what it uses and nothing of the others
COMMANDS = {
    "list": ("commands", "list_templates"),
    "new": ("commands", "copy_template"),
    "check": ("commands", "check_template"),
    "build": ("commands", "build"),
    "verify": ("verdict", "verify"),
    "preview": ("commands", "preview_pages"),
    "animate": ("commands", "animate"),
    "info": ("commands", "summarise"),
    "export": ("commands", "export_tables"),
}


def run() -> None:
    """The `linkbook` command and `python -m linkbook`: main(), then the process ends at once.
    By then everything a command makes is closed (files written and renamed into place,
    LibreOffice waited for); what Python's own exit would add is freeing the book's hundreds of
    thousands of objects one by one and tearing down every module: 30-60 ms of a 0.3-0.5 s build
    or verify, measured here. The exit handlers still run (openpyxl removes its temporary files
    after a failed save, coverage saves its data), and under a profiler or tracer, which reports
    after we return, the exit is Python's own. Callers of main() (the tests, the API) keep a
    normal return."""
    with stopping.handled():      # first: from here to the exit a signal ends in one line
        status = main(exiting=True)
        if sys.getprofile() is not None or sys.gettrace() is not None:
            raise SystemExit(status)
        with stopping.held():     # one that comes now is looked at once, just before the exit
            _finish()
            stop = stopping.arrived()
            if stop is not None and status not in STOPPED_STATUSES:
                _say_stopped(stop[0])
                status = stop[1]
            os._exit(status)


def _finish() -> None:
    """What Python's own exit would do that matters: the exit handlers, the streams flushed."""
    import atexit
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        if stream is None:          # started with the stream closed
            continue
        try:
            stream.flush()
        except BrokenPipeError:     # the reader stopped early, as in main()
            _to_devnull(stream)
        except (OSError, ValueError):
            pass


def _say_stopped(what: str) -> None:
    print(f"linkbook: stopped by {what}; no file is left half-written", file=sys.stderr,
          flush=True)


STOPPED_STATUSES = {status for _, _, status in stopping.STOPS.values()}


def _to_devnull(stream) -> None:
    os.dup2(os.open(os.devnull, os.O_WRONLY), stream.fileno())


def main(argv: list[str] | None = None, exiting: bool = False) -> int:
    """The command `argv` (the process's own arguments: None) run, its exit status returned.
    `exiting`: the process ends when this returns (run()), so Python's cyclic collector is off
    to the exit, and on between books (base/pause.py)."""
    # Everything inside the try, from the first line on: a Ctrl-C that lands while the command
    # is still being imported ends in the same one line as one that lands mid-work.
    try:
        import warnings
        if exiting:
            from ..base import pause
            pause.pause_until_exit()
        with stopping.handled(), warnings.catch_warnings():
            # numpy's overflow warnings on extreme inputs would only repeat what the answer
            # says, and no user should see a line of our source code
            warnings.simplefilter("ignore")
            status = _main(argv)
            stopping.stop_if_signalled()     # one whose raise was swallowed where it landed
            return status
    except BrokenPipeError:
        # The reader stopped early (`linkbook list | head`): not an error. Point stdout at
        # /dev/null so that Python's own flush at exit does not complain either.
        _to_devnull(sys.stdout)
        return 0
    except BaseException as exc:
        # a stop, or anything a stop turned into on its way out (a library's own error)
        stop = stopping.stop_of(exc) or stopping.arrived()
        if stop is not None:
            what, status = stop      # the shell's convention: 128 + the signal's number
            _say_stopped(what)
            return status
        if not isinstance(exc, Exception):      # SystemExit: argparse's own exit
            raise
        # A bug of ours, not the user's input: still one line, never a traceback.
        print(f"linkbook: internal error: {type(exc).__name__}: {_one_line(exc)} (please "
              "report it with the file that caused it)", file=sys.stderr)
        return 2


def _main(argv: list[str] | None) -> int:
    from importlib import import_module
    from ..base.files import CannotWrite
    from .arguments import parser
    from .lines import error
    args = parser().parse_args(argv)
    module, function = COMMANDS[args.command]
    command = getattr(import_module(f".{module}", __package__), function)
    try:
        return command(args)
    except (InputError, CannotWrite) as exc:
        error(exc)
        return 2


def _one_line(exc: Exception) -> str:
    text = " ".join(str(exc).split())
    return text if len(text) <= 300 else text[:297] + "..."


if __name__ == "__main__":
    run()
