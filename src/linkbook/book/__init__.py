"""The writer: a compiled mechanism laid out as sheets, charts, form controls and page setup,
saved by openpyxl and finished by one pass over the package."""
