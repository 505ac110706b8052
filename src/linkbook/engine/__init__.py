"""Evaluating a book: the formula grammar, the vector engine over `formulas`' functions, and
LibreOffice or Gnumeric run headless as a second opinion."""
