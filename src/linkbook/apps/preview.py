"""`linkbook preview`: the printed pages of a book as PNG (and the whole print as PDF), made by
LibreOffice and poppler's pdftoppm."""
from __future__ import annotations

import re
import shutil
import tempfile
import zipfile
from pathlib import Path

from ..engine.errors import OfficeFailed, OfficeUnavailable

PREVIEW_DPI = 110          # a table's small print stays readable

# ---------------------------------------------------------------- pictures
def preview(path, outdir, dpi: int = PREVIEW_DPI, sheets: list[str] | None = None
            ) -> list[Path]:
    """The printed pages (sheets and charts) as PNG, and the whole print as PDF: soffice ->
    PDF -> pdftoppm, one sheet at a time so that each picture is named by its sheet.

    `sheets`: the visible sheets to print (default: all, in the book's order). Writes
    STEM.pdf (those sheets, in order) and STEM-SHEET-1.png, STEM-SHEET-2.png, ... per sheet
    (SHEET with anything but letters, digits, - and _ as _; pdftoppm pads the number with zeros
    when a sheet prints ten or more pages). Returns the pictures in print order."""
    # here, not at the top: the argument parser imports this module for PREVIEW_DPI
    from ..engine.office import _run, to_pdf_all
    pdftoppm = shutil.which("pdftoppm")
    if pdftoppm is None:
        raise OfficeUnavailable("pdftoppm (Debian package poppler-utils) is needed for PNG "
                                "previews: apt-get install -y poppler-utils")
    path, outdir = Path(path), Path(outdir)
    chosen = list(sheets) if sheets else visible_sheets(path)
    outdir.mkdir(parents=True, exist_ok=True)
    stem = path.stem
    with tempfile.TemporaryDirectory(prefix="linkbook-pdf-") as tmp:
        names = [f"{stem}-{_file_word(sheet)}" for sheet in chosen]
        copies = [_only_sheets(path, chosen, Path(tmp, "all"))] + [
            _only_sheets(path, [sheet], Path(tmp, name), name)
            for sheet, name in zip(chosen, names)]
        # every copy printed in one run of soffice: one start-up, not one a sheet
        whole, *pdfs = to_pdf_all(copies, tmp)
        shutil.move(str(whole), outdir / f"{stem}.pdf")
        out = []
        for sheet, name, pdf in zip(chosen, names, pdfs):
            pictures = Path(tmp, "png", name)
            pictures.mkdir(parents=True)
            code, detail = _run([pdftoppm, "-png", "-r", str(dpi), str(pdf),
                                 str(pictures / name)], f"rendering {sheet}")
            if code != 0:
                raise OfficeFailed(f"pdftoppm failed on {sheet} (exit {code}): {detail}")
            # Rendered apart, then moved: pages of an earlier, longer preview are never returned.
            made = sorted(pictures.glob("*.png"), key=_page_number)
            if not made:
                raise OfficeFailed(f"no pages were rendered from sheet {sheet!r}")
            # pdftoppm pads the page number to the page count's digits (-01 of 12 pages)
            out += [Path(shutil.move(str(p), outdir / f"{name}-{_page_number(p)}.png"))
                    for p in made]
        return out


_SHEET_TAG = re.compile(r"<sheet\b[^>]*/>")


def visible_sheets(path) -> list[str]:
    """The names of the book's visible sheets, in order (read from the file's workbook part,
    without loading the workbook)."""
    with zipfile.ZipFile(path) as z:
        xml = z.read("xl/workbook.xml").decode("utf-8")
    return [name for name, state in _sheet_tags(xml) if state == "visible"]


def _sheet_tags(xml: str) -> list[tuple[str, str]]:
    out = []
    for tag in _SHEET_TAG.findall(xml):
        name = _sheet_name(tag)
        state = re.search(r'\bstate="([^"]*)"', tag)
        out.append((name, state.group(1) if state else "visible"))
    return out


def _sheet_name(tag: str) -> str:
    # html only here: every command imports this module for PREVIEW_DPI (its help text)
    from html import unescape
    return unescape(re.search(r'\bname="([^"]*)"', tag).group(1))


def _only_sheets(path: Path, sheets: list[str], folder: Path, name: str | None = None) -> Path:
    """A copy of the book (named `name`.xlsx, or as the book), byte for byte but for its
    workbook part, in which only `sheets` are visible (the first of them active): LibreOffice
    prints visible sheets only. No page prints the file's name (its footer: the sheet, the
    page)."""
    folder.mkdir(parents=True, exist_ok=True)
    copy = folder / (f"{name}.xlsx" if name else path.name)
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(copy, "w", zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "xl/workbook.xml":
                data = _show_only(data.decode("utf-8"), sheets).encode("utf-8")
            dst.writestr(item, data)
    return copy


def _show_only(xml: str, sheets: list[str]) -> str:
    names = [name for name, _ in _sheet_tags(xml)]
    active = names.index(sheets[0])

    def state(match: re.Match) -> str:
        tag = re.sub(r'\s*\bstate="[^"]*"', "", match.group(0))
        name = _sheet_name(tag)
        return tag if name in sheets else tag.replace("<sheet ", '<sheet state="hidden" ', 1)
    xml = _SHEET_TAG.sub(state, xml)
    # LibreOffice prints a hidden sheet that has a print area: the hidden sheets' go
    hidden = {str(k) for k, name in enumerate(names) if name not in sheets}
    xml = re.sub(r'<definedName name="_xlnm\.Print_(?:Area|Titles)" localSheetId="(\d+)"'
                 r'[^>]*>[^<]*</definedName>',
                 lambda m: "" if m.group(1) in hidden else m.group(0), xml)
    xml = re.sub(r'\bactiveTab="\d+"', f'activeTab="{active}"', xml)
    return re.sub(r'\bfirstSheet="\d+"', f'firstSheet="{active}"', xml)


def _file_word(sheet: str) -> str:
    """A sheet's name as part of a file name: `Drawing data` → `Drawing_data`."""
    return re.sub(r"[^A-Za-z0-9_-]+", "_", sheet).strip("_") or "sheet"


def _page_number(p: Path) -> int:
    tail = p.stem.rsplit("-", 1)[-1]
    return int(tail) if tail.isdigit() else 0
