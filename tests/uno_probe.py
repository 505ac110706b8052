"""Load a workbook in LibreOffice through its own API (UNO) and report its form controls.

Run by tests/test_controls.py with the Python that has LibreOffice's `uno` module (Debian's
python3-uno, for /usr/bin/python3), not the project's Python:

    python3 uno_probe.py BOOK.xlsx SHEET MOVES_JSON CELLS_JSON

MOVES_JSON is a list of [control index, new value]; CELLS_JSON a list of cell addresses on SHEET.
For each move, the control's value is set through its model (as a click does), the document is
recalculated and the cells are read. Prints one JSON object: the controls (type, range, steps,
linked cell, value, position) and the cells' values before and after each move.
"""
from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import uno
from com.sun.star.beans import PropertyValue

KINDS = {"com.sun.star.form.component.SpinButton": "Spin",
         "com.sun.star.form.component.ScrollBar": "Scroll"}
PROPS = {"Spin": ("SpinValueMin", "SpinValueMax", "SpinIncrement", None, "SpinValue"),
         "Scroll": ("ScrollValueMin", "ScrollValueMax", "LineIncrement", "BlockIncrement",
                    "ScrollValue")}


HANG_GUARD_S = 300      # conftest's: only a hung LibreOffice takes this long to listen


def connect(pipe: str, office: subprocess.Popen):
    """The office's context, once it listens on the pipe: waited for as long as the office
    runs (a loaded machine starts it slowly), not for a fixed time; HANG_GUARD_S only
    against a hang."""
    local = uno.getComponentContext()
    resolver = local.ServiceManager.createInstanceWithContext(
        "com.sun.star.bridge.UnoUrlResolver", local)
    give_up = time.monotonic() + HANG_GUARD_S
    while True:
        try:
            return resolver.resolve(f"uno:pipe,name={pipe};urp;StarOffice.ComponentContext")
        except Exception:
            if office.poll() is not None or time.monotonic() > give_up:
                raise
            time.sleep(0.3)


def prop(name: str, value) -> PropertyValue:
    p = PropertyValue()
    p.Name, p.Value = name, value
    return p


def controls_of(sheet) -> list[tuple[dict, object]]:
    out = []
    page = sheet.DrawPage
    for i in range(page.Count):
        shape = page.getByIndex(i)
        if not shape.supportsService("com.sun.star.drawing.ControlShape"):
            continue
        model = shape.Control
        kind = next((k for s, k in KINDS.items() if model.supportsService(s)), None)
        info = {"kind": kind or model.getImplementationName(), "name": model.Name,
                "printable": bool(model.Printable),
                "position": [shape.Position.X, shape.Position.Y],
                "size": [shape.Size.Width, shape.Size.Height]}
        if kind:
            lo, hi, inc, page_step, value = PROPS[kind]
            info.update(min=model.getPropertyValue(lo), max=model.getPropertyValue(hi),
                        inc=model.getPropertyValue(inc), value=model.getPropertyValue(value),
                        page=model.getPropertyValue(page_step) if page_step else None)
            if kind == "Scroll":
                info["horizontal"] = model.Orientation == 0
        binding = model.getValueBinding() if hasattr(model, "getValueBinding") else None
        if binding is not None:
            cell = binding.getPropertyValue("BoundCell")
            info["cell"] = [cell.Sheet, cell.Column, cell.Row]
        out.append((info, model))
    return out


def read(sheet, cells: list[str]) -> dict:
    out = {}
    for ref in cells:
        cell = sheet.getCellRangeByName(ref)
        text = cell.getString()
        out[ref] = cell.getValue() if cell.getError() == 0 and cell.getType().value != "TEXT" \
            else text
        if cell.getError():
            out[ref] = f"#ERR{cell.getError()}"
    return out


@contextlib.contextmanager
def running_office(name: str):
    """A headless LibreOffice of its own (a fresh profile, a pipe named after `name` and this
    process), its Desktop yielded; ended whatever happens."""
    pipe = f"linkbook_{name}_{os.getpid()}"
    with tempfile.TemporaryDirectory(prefix="linkbook-uno-") as profile:
        office = subprocess.Popen(
            ["soffice", f"-env:UserInstallation={Path(profile).as_uri()}", "--headless",
             "--invisible", "--norestore", "--nologo", "--nolockcheck",
             f"--accept=pipe,name={pipe};urp;"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            start_new_session=True)
        desktop = None
        try:
            ctx = connect(pipe, office)
            desktop = ctx.ServiceManager.createInstanceWithContext(
                "com.sun.star.frame.Desktop", ctx)
            yield desktop
        finally:
            if desktop is not None:
                try:
                    desktop.terminate()
                except Exception:
                    pass
            try:
                office.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(office.pid, 9)


def main() -> None:
    book, sheet_name, moves, cells = sys.argv[1], sys.argv[2], json.loads(sys.argv[3]), \
        json.loads(sys.argv[4])
    with running_office("probe") as desktop:
        doc = desktop.loadComponentFromURL(Path(book).resolve().as_uri(), "_blank", 0,
                                           (prop("Hidden", True),))
        doc.calculateAll()
        sheet = doc.Sheets.getByName(sheet_name)
        found = controls_of(sheet)
        report = {"controls": [info for info, _ in found], "before": read(sheet, cells),
                  "after": []}
        for index, value in moves:
            info, model = found[index]
            model.setPropertyValue(PROPS[info["kind"]][4], value)
            doc.calculateAll()
            report["after"].append(read(sheet, cells))
        doc.close(True)
        print(json.dumps(report))


if __name__ == "__main__":
    main()
