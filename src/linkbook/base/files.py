"""Writing files so that an existing one is never left half-written, and saying in one line why
a file or folder cannot be written (a full disk, a read-only mount, a folder where a file belongs)."""
from __future__ import annotations

import errno
import os
import tempfile
from pathlib import Path
from typing import Callable

from .errors import InputError
from .stopping import held, stop_if_signalled

# What the environment did, in words: the reason a write failed is the user's to fix, not ours.
REASONS = {
    errno.ENOSPC: "the disk is full",
    errno.EDQUOT: "the disk quota is used up",
    errno.EROFS: "the file system is read-only",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.EISDIR: "it is a folder, not a file",
    errno.ENOTDIR: "a part of the path is a file, not a folder",
    errno.ENOENT: "the folder does not exist",
    errno.ENAMETOOLONG: "the name is too long",
}


class CannotWrite(OSError):
    """The environment refused a write (exit 2): one line naming the target and the reason.
    An OSError, so that callers catching OSError still catch it; its errno is the original's."""

    def __init__(self, path: Path, exc: OSError, action: str = "write"):
        reason = REASONS.get(exc.errno) or exc.strerror or " ".join(str(exc).split())
        super().__init__(exc.errno, reason, str(path))
        self.message = f"cannot {action} {path}: {reason}"

    def __str__(self) -> str:
        return self.message


def check_output(path: Path, field: str, suffixes: tuple[str, ...]) -> Path:
    """An output path the user named (`field`: the flag or argument that named it): a file
    with one of `suffixes`, not a folder, in a folder that exists. InputError otherwise."""
    path = Path(path)
    if path.is_dir():
        raise InputError(field, f"{str(path)!r} is a folder; name a file in it")
    if path.suffix.lower() not in suffixes:
        wanted = " or ".join(suffixes)
        raise InputError(field, f"must name an {wanted} file (got {str(path)!r})")
    parent = path.parent
    if parent.exists() and not parent.is_dir():
        raise InputError(field, f"{str(parent)!r} is a file, not a folder")
    if not parent.is_dir():
        raise InputError(field, f"folder {str(parent)!r} does not exist")
    return path


def ensure_folder(path: Path, field: str) -> Path:
    """A folder to write into, made if missing; InputError if a file is in its place,
    CannotWrite if the file system refuses to make it."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError(field, f"{str(path)!r} is a file, not a folder")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CannotWrite(path, exc, "make the folder") from None
    return path


def write_atomic(path: Path, write: Callable[[Path], None]) -> None:
    """Let `write` fill a temporary file beside the target, then rename it into place: an
    existing file is never left half-written, whatever happens before the rename, and the
    temporary file is removed whatever ends the write (an error, Ctrl-C, SIGTERM turned into an
    exception by the command). A signal that came before the rename, even one whose exception
    was swallowed (see stopping), stops it: the target is left as it was. The file system's
    refusal is raised as CannotWrite naming the target, never the temporary file."""
    path = Path(path)
    tmp = None
    try:
        with held():                       # the temporary file exists only once `tmp` names it
            fd, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
            tmp = Path(name)
        os.close(fd)
        write(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)      # mkstemp makes it private; a workbook is not
        with held():                       # no signal can come between the look and the rename
            stop_if_signalled()
            os.replace(tmp, path)
    except OSError as exc:
        raise CannotWrite(path, exc) from None
    finally:
        if tmp is not None and os.path.exists(tmp):
            os.unlink(tmp)
