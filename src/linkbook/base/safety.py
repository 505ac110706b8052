"""Open a workbook someone handed us without trusting it.

An .xlsx is a zip of XML parts. Before openpyxl parses anything we check that the file is a zip
that is complete, that it would not inflate to something huge (a zip bomb), and that no part
declares a DTD or entities anywhere in it (billion laughs, external entities). openpyxl itself
parses with defusedxml when it is installed, which pyproject requires.
"""
from __future__ import annotations

import re
import zipfile
from pathlib import Path

MAX_UNCOMPRESSED = 512 * 1024 * 1024     # a 1,048,576-row sheet of numbers stays below this
MAX_RATIO = 200                          # real workbooks compress about 5-20 times
MAX_PARTS = 10_000
DTD_MARKERS = ("<!DOCTYPE", "<!ENTITY")
# A part may be UTF-8 or UTF-16 (either byte order): the markers in each encoding.
_DTD = re.compile(b"|".join(re.escape(m.encode(e)) for m in DTD_MARKERS
                            for e in ("utf-8", "utf-16-le", "utf-16-be")))
_LONGEST_MARKER = max(len(m.encode("utf-16-le")) for m in DTD_MARKERS)
_CHUNK = 1 << 20


class UnsafeFile(Exception):
    """The file is not a workbook we are willing to open (exit 2)."""


def check_zip(path: Path) -> None:
    """Refuse a file that is no workbook we are willing to open (see the module's docstring):
    every part is scanned."""
    _check_zip(path)


def _check_zip(path: Path, defer=None) -> tuple[list[str], dict[str, bool]]:
    """check_zip, but for the parts `defer` (a test on a part's name) names, which are left
    to the caller to scan as it reads them (PartGuard), the external references with them: the
    names of the parts deferred, and whether each part scanned holds a '['."""
    path = Path(path)
    if path.is_dir():
        raise UnsafeFile(f"{path}: a folder, not a workbook")
    if not path.is_file():
        raise UnsafeFile(f"{path}: no such file")
    if not zipfile.is_zipfile(path):
        raise UnsafeFile(f"{path}: not an .xlsx workbook (not a zip file)")
    try:
        with zipfile.ZipFile(path) as zf:
            infos = zf.infolist()
            if len(infos) > MAX_PARTS:
                raise UnsafeFile(f"{path}: {len(infos)} parts; refusing an unusual archive")
            total = sum(i.file_size for i in infos)
            packed = sum(i.compress_size for i in infos) or 1
            if total > MAX_UNCOMPRESSED or (total > 10_000_000 and total / packed > MAX_RATIO):
                raise UnsafeFile(f"{path}: would inflate to {total:,} bytes; refusing a "
                                 "possible zip bomb")
            if "[Content_Types].xml" not in zf.namelist():
                raise UnsafeFile(f"{path}: not an .xlsx workbook (no [Content_Types].xml)")
            deferred = [i.filename for i in infos if defer is not None and defer(i.filename)]
            left = set(deferred)
            bracketed = {info.filename: _check_part(zf, info, path) for info in infos
                         if info.filename not in left}
            if defer is None:
                _check_external(zf, [name for name, bracket in bracketed.items() if bracket],
                                path)
            return deferred, bracketed
    except zipfile.BadZipFile as exc:
        raise UnsafeFile(f"{path}: damaged or truncated workbook ({exc})") from None
    except UnsafeFile:
        if defer is None:
            raise
        check_zip(path)     # a deferred part before it may be unsafe too: the first one's answer
        raise


class PartGuard:
    """check_zip's scan of one part, fed the part's bytes as they are read (each chunk before
    anything parses it): a DTD or entity declaration anywhere refused, and whether the part
    holds a '[' (which a formula naming another workbook has). `whole`: fed to its end;
    `refused`: it raised UnsafeFile."""

    def __init__(self, part: str, path: Path):
        self.part, self.path = part, path
        self.tail, self.bracket, self.whole, self.refused = b"", False, False, False

    def __call__(self, chunk: bytes) -> None:
        if not chunk:
            self.whole = True
            return
        self.bracket = self.bracket or b"[" in chunk
        window = self.tail + chunk
        # every marker starts '<!' (UTF-8) or '<\0!' (UTF-16): two fast finds rule most
        # chunks out before the regex, which is four times slower
        if (b"<!" in window or b"<\x00!" in window) and _DTD.search(window):
            self.refused = True
            raise UnsafeFile(f"{self.path}: part {self.part} declares a DTD or XML "
                             "entities; refusing")
        self.tail = chunk[-_LONGEST_MARKER:]


def _check_part(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path: Path) -> bool:
    """Refuse a part that holds a DTD or entity declaration anywhere. A DTD belongs before
    the root element, but a reader may meet one after any length of comments, and a part is
    XML by its content type, not its name: every part is scanned whole, a chunk at a time (a
    chunk keeps the tail of the one before, so a marker split between two is found). Whether
    the part holds a '[': the scan tells."""
    guard = PartGuard(info.filename, path)
    with zf.open(info) as f:
        while True:
            chunk = f.read(_CHUNK)
            guard(chunk)
            if not chunk:
                return guard.bracket


def _check_external(zf: zipfile.ZipFile, bracketed: list[str], path: Path) -> None:
    """Refuse a book that names another file for its formulas to read (an external link):
    no engine and no application may open a file the book names outside itself. Refused
    here, where every reader of a book starts, before any engine or application sees it."""
    from . import xlsx
    found = xlsx.external_reference(zf, bracketed)
    if found:
        raise UnsafeFile(f"{path}: {found}; linkbook reads no file but the book")


def load_workbook_safely(path: Path, data_only: bool = False):
    import openpyxl
    check_zip(path)
    try:
        return openpyxl.load_workbook(path, data_only=data_only)
    except Exception as exc:  # openpyxl raises many kinds on a damaged file
        # its messages run over several lines ("... Please see the exception ..."): one line
        said = " ".join(str(exc).split())
        raise UnsafeFile(f"{path}: cannot be read as a workbook ({type(exc).__name__}: "
                         f"{said})") from None


def read_workbook_safely(path: Path):
    """The book's cells and names for reading only: the fast view (linkbook.base.xlsx) where it
    models the file, else openpyxl's full load (which also words the error of a damaged
    file). The worksheet parts the view reads are scanned as it reads them (PartGuard), not
    inflated once more before: any refusal is still check_zip's, in check_zip's order."""
    from . import xlsx
    deferred, bracketed = _check_zip(path, defer=_is_worksheet)
    guards = {part: PartGuard(part, path) for part in deferred}
    try:
        wb = xlsx.read(path, guards)
    except UnsafeFile:
        check_zip(path)     # what check_zip says first (another part may be unsafe too)
        raise
    except xlsx.Refused as exc:
        check_zip(path)     # a part the view did not reach is refused first
        raise UnsafeFile(f"{path}: {exc}") from None
    except Exception:   # xlsx.Unsupported, or a part openpyxl will judge
        return load_workbook_safely(path)
    with zipfile.ZipFile(path) as zf:
        for part in deferred:
            if not guards[part].whole:          # a part the view did not read to its end
                guards[part].bracket = _check_part(zf, zf.getinfo(part), path)
            bracketed[part] = guards[part].bracket
        order = [info.filename for info in zf.infolist()]
        _check_external(zf, [n for n in order if bracketed.get(n)], path)
    return wb


def _is_worksheet(part: str) -> bool:
    return part.startswith("xl/worksheets/") and part.endswith(".xml")
