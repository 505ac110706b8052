"""Edit a workbook's cells in LibreOffice through its own API (UNO) and save it as .xlsx, as a
user who opens the book, types new inputs and saves does.

Run by tests/test_round_trip.py with the Python that has LibreOffice's `uno` module (Debian's
python3-uno, for /usr/bin/python3), not the project's Python:

    python3 uno_edit.py BOOK.xlsx OUT.xlsx EDITS_JSON

EDITS_JSON maps 'Sheet!A1' to a number or a text. Each is typed into its cell (a text starting
with '=' as a formula), the document is recalculated and stored with LibreOffice's Excel 2007-365
filter. Prints one JSON object: the edited cells' values after the recalculation.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

from uno_probe import prop, running_office

XLSX_FILTER = "Calc MS Excel 2007 XML"


def edit(doc, address: str, value) -> None:
    sheet_name, cell_name = address.rsplit("!", 1)
    cell = doc.Sheets.getByName(sheet_name.strip("'")).getCellRangeByName(cell_name)
    if isinstance(value, str) and value.startswith("="):
        cell.setFormula(value)
    elif isinstance(value, str):
        cell.setString(value)
    else:
        cell.setValue(float(value))


def main() -> None:
    book, out, edits = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
    with running_office("edit") as desktop:
        doc = desktop.loadComponentFromURL(Path(book).resolve().as_uri(), "_blank", 0,
                                           (prop("Hidden", True),))
        for address, value in edits.items():
            edit(doc, address, value)
        doc.calculateAll()
        after = {}
        for address in edits:
            sheet_name, cell_name = address.rsplit("!", 1)
            cell = doc.Sheets.getByName(sheet_name.strip("'")).getCellRangeByName(cell_name)
            after[address] = cell.getValue() if cell.getType().value == "VALUE" \
                else cell.getString()
        doc.storeToURL(Path(out).resolve().as_uri(),
                       (prop("FilterName", XLSX_FILTER), prop("Overwrite", True)))
        doc.close(True)
        print(json.dumps(after))


if __name__ == "__main__":
    main()
