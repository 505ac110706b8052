"""LibreOffice and Gnumeric, headless: real spreadsheet applications as checkers, and
LibreOffice as a printer.

A recalculation is one mechanism for both applications: the application loads the book, computes
every formula and saves an .xlsx into a scratch folder, whose values are then read back. LibreOffice
(`soffice`) runs with a private, freshly made profile (two jobs sharing one profile lose output)
whose settings force a full recalculation on load: it would otherwise keep whatever values a file
caches, or none. Gnumeric (`ssconvert --recalc`) recalculates every cell when told to. Both exit 0
even when they fail, so each call checks that the file it asked for exists. Temporary folders are
always removed.

Errors: a formula's cached error comes back from openpyxl (data_only) as the plain string of its
code with data_type 'e' ('#N/A', '#NUM!', '#DIV/0!', '#VALUE!', '#NAME?', ...).
`recalculated_values` wraps those in `CellError`, a str subclass, so an error is never taken for a
text result. LibreOffice differs from Excel on a few: SQRT(-1) is #VALUE! (Excel #NUM!),
ATAN2(0, 0) is 0 (Excel #DIV/0!). Gnumeric writes its error values with Excel's codes, and gives
Excel's answer on both; Debian's Gnumeric 1.12.55 computes in long double and writes 21 digits
(1/3 is 0.333333333333333333342), read back here as the nearest double.
"""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import tempfile
from contextlib import contextmanager
from pathlib import Path

from ..base.xlsx import CellError, error_code, is_error  # noqa: F401  (a recalculation is read with these)
from .errors import OfficeFailed, OfficeUnavailable  # noqa: F401  (raised here; callers take them)

TIMEOUT_S = 300
XLSX_FILTER = "xlsx:Calc MS Excel 2007 XML"
PDF_FILTER = "pdf:calc_pdf_Export"
INSTALL_HINT = ("LibreOffice is needed for this (the `soffice` command was not found). "
                "Install it, e.g. on Debian/Ubuntu: apt-get install -y --no-install-recommends "
                "libreoffice-calc-nogui; for PNG previews also poppler-utils (pdftoppm).")
GNUMERIC_HINT = ("Gnumeric is needed for this (the `ssconvert` command was not found). "
                 "Install it, e.g. on Debian/Ubuntu: apt-get install -y --no-install-recommends "
                 "gnumeric.")
# the applications a book can be recalculated in (verify's engines of the same names)
APPLICATIONS = ("libreoffice", "gnumeric")

# Recalculation modes 0 = always, 1 = never, 2 = ask: "always" for files from Excel (OOXML) and
# from LibreOffice (ODF). Written into the private profile before soffice first starts.
REGISTRY = """<?xml version="1.0" encoding="UTF-8"?>
<oor:items xmlns:oor="http://openoffice.org/2001/registry" \
xmlns:xs="http://www.w3.org/2001/XMLSchema" xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance">
<item oor:path="/org.openoffice.Office.Calc/Formula/Load">\
<prop oor:name="OOXMLRecalcMode" oor:op="fuse"><value>0</value></prop></item>
<item oor:path="/org.openoffice.Office.Calc/Formula/Load">\
<prop oor:name="ODFRecalcMode" oor:op="fuse"><value>0</value></prop></item>
</oor:items>
"""


# ---------------------------------------------------------------- running soffice
def soffice_path() -> str | None:
    return shutil.which("soffice") or shutil.which("libreoffice")


def _require_soffice() -> str:
    exe = soffice_path()
    if exe is None:
        raise OfficeUnavailable(INSTALL_HINT)
    return exe


def ssconvert_path() -> str | None:
    return shutil.which("ssconvert")


def _require_ssconvert() -> str:
    exe = ssconvert_path()
    if exe is None:
        raise OfficeUnavailable(GNUMERIC_HINT)
    return exe


@contextmanager
def _profile():
    """A fresh LibreOffice user profile that recalculates every file on load."""
    with tempfile.TemporaryDirectory(prefix="linkbook-lo-") as tmp:
        user = Path(tmp, "user")
        user.mkdir()
        (user / "registrymodifications.xcu").write_text(REGISTRY, encoding="utf-8")
        yield Path(tmp).as_uri()


def _convert(paths: list[Path], outdir: Path, target: str, suffix: str) -> list[Path]:
    """soffice --convert-to TARGET of every book in one run (one start-up for them all) into a
    scratch folder, then move the results into outdir."""
    exe = _require_soffice()
    with _profile() as profile:
        return _made_by("LibreOffice", paths, outdir, suffix, lambda sources, scratch: [
            exe, f"-env:UserInstallation={profile}", "--headless", "--norestore",
            "--nolockcheck", "--calc", "--convert-to", target, "--outdir", str(scratch),
            *map(str, sources)])


def _gnumeric_recalculate(path: Path, outdir: Path) -> Path:
    """ssconvert --recalc: every formula computed by Gnumeric, saved as .xlsx (Excel 2007+)."""
    exe = _require_ssconvert()
    return _made_by("Gnumeric", [path], outdir, ".xlsx", lambda sources, scratch: [
        exe, "--recalc", "--export-type=Gnumeric_Excel:xlsx2", str(sources[0]),
        str(scratch / (sources[0].stem + ".xlsx"))])[0]


def _made_by(application: str, paths: list[Path], outdir: Path, suffix: str,
             command) -> list[Path]:
    """Run `command(sources, scratch folder)`, which writes each STEM+suffix into the scratch
    folder, and move those files into outdir."""
    paths = [Path(p).resolve() for p in paths]
    for path in paths:
        if not path.is_file():
            raise FileNotFoundError(path)
    if len({p.stem for p in paths}) < len(paths):
        raise ValueError("books of the same name would convert to one file: convert them apart")
    outdir = Path(outdir)
    outs = [outdir / (path.stem + suffix) for path in paths]
    for out, path in zip(outs, paths):
        if out.resolve() == path:           # the application's copy is not the file we wrote
            raise ValueError(f"{out} would replace its own source: choose another outdir")
    outdir.mkdir(parents=True, exist_ok=True)
    names = ", ".join(path.name for path in paths)
    with tempfile.TemporaryDirectory(prefix="linkbook-out-") as scratch:
        code, detail = _run(command(paths, Path(scratch)), f"converting {names}")
        for out, path in zip(outs, paths):
            made = Path(scratch, out.name)
            if not made.is_file() or made.stat().st_size == 0:
                raise OfficeFailed(f"{application} could not convert {path.name} to {suffix} "
                                   f"(exit {code}){': ' + _last_line(detail) if detail else ''}")
            shutil.move(str(made), out)
    return outs


def _last_line(detail: str) -> str:
    """An application's last words: Gnumeric prints a warning per element it does not know
    before the one that says why it failed."""
    return detail.strip().splitlines()[-1].strip() if detail.strip() else ""


def _run(cmd: list[str], what: str) -> tuple[int, str]:
    """Run a command in a process group of its own, so that a time-out ends soffice.bin too
    (soffice is a launcher script that starts it as a child)."""
    proc = subprocess.Popen(cmd, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        stdout, stderr = proc.communicate(timeout=TIMEOUT_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise OfficeFailed(f"{Path(cmd[0]).name} did not finish {what} within {TIMEOUT_S} s") \
            from None
    except BaseException:
        # Ctrl-C or SIGTERM reached only us (the command has a session of its own): end it too
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        raise
    return proc.returncode, (stderr or stdout).strip()


def recalculate(path, outdir, application: str = "libreoffice") -> Path:
    """Load in the application (one of APPLICATIONS) with a full recalculation and save as
    .xlsx into outdir."""
    if application == "gnumeric":
        return _gnumeric_recalculate(Path(path), Path(outdir))
    if application != "libreoffice":
        raise ValueError(f"no application {application!r}: one of {', '.join(APPLICATIONS)}")
    return _convert([Path(path)], Path(outdir), XLSX_FILTER, ".xlsx")[0]


def recalculate_all(paths, outdir) -> list[Path]:
    """recalculate() in LibreOffice of several books in one run of soffice (one start-up, not
    one a book): each saved as .xlsx into outdir, in the order given."""
    return _convert([Path(p) for p in paths], Path(outdir), XLSX_FILTER, ".xlsx")


def to_pdf(path, outdir) -> Path:
    """Print every visible sheet (and its charts) to PDF, as the workbook's page setup says."""
    return to_pdf_all([path], outdir)[0]


def to_pdf_all(paths, outdir) -> list[Path]:
    """to_pdf() of several books in one run of soffice, in the order given."""
    return _convert([Path(p) for p in paths], Path(outdir), PDF_FILTER, ".pdf")


# ---------------------------------------------------------------- reading values back
def read_values(path) -> dict[tuple[str, str], object]:
    """(sheet title, 'B7') -> the cached value of every non-empty cell of an .xlsx file."""
    import warnings
    import openpyxl
    with warnings.catch_warnings():
        # about the application's copy, not the book: Gnumeric writes no default cell style
        # and a print area of several ranges as ERROR("..."), which openpyxl reports
        warnings.simplefilter("ignore", UserWarning)
        wb = openpyxl.load_workbook(path, data_only=True, read_only=True)
    try:
        values = {}
        for ws in wb.worksheets:
            for row in ws.iter_rows():
                for c in row:
                    value = _value(c)
                    if value is not None:
                        values[(ws.title, c.coordinate)] = value
        return values
    finally:
        wb.close()


def _value(cell):
    if not hasattr(cell, "coordinate"):             # read-only padding for a missing cell
        return None
    if cell.data_type == "e":
        return CellError(str(cell.value))
    if cell.value is None:
        # A formula whose result is "" is cached as t="str" with an empty <v>.
        return "" if cell.data_type == "str" else None
    if isinstance(cell.value, int) and not isinstance(cell.value, bool):
        return float(cell.value)
    return cell.value


def recalculated_values(path, application: str = "libreoffice") -> dict[tuple[str, str], object]:
    """Every cell's value after the application (LibreOffice or Gnumeric) has recalculated a
    copy: numbers as float, errors as CellError, text as str ('' for a formula whose result is
    empty text), booleans as bool."""
    with tempfile.TemporaryDirectory(prefix="linkbook-recalc-") as tmp:
        return read_values(recalculate(path, tmp, application))
