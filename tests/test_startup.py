"""What a verify does once that it used to do more than once (issue 42, start-up)."""
from __future__ import annotations

import pytest

from linkbook.book import builder
from linkbook.check import verifier
from linkbook.language import bundled, templates

BOOKS = ("fourbar", "slider-crank")


@pytest.fixture(scope="module")
def books(tmp_path_factory) -> dict:
    folder = tmp_path_factory.mktemp("startup")
    paths = {name: folder / f"{name}.xlsx" for name in BOOKS}
    for name, path in paths.items():
        builder.build_file(templates.load(name), path)
    return paths


def test_verify_compiles_the_recorded_mechanism_once_per_book(books, monkeypatch):
    """The book's own judging, the other input sets' draw and their judging share one compiled
    mechanism; a second book gets its own."""
    compiled = []
    real = bundled.from_record

    def counted(record):
        compiled.append(record.mechanism)
        return real(record)
    monkeypatch.setattr(bundled, "from_record", counted)
    for name, path in books.items():
        report = verifier.verify(path)
        assert report.ok and report.mechanism == name
        assert [s.skipped for s in report.input_sets] == [None]      # judged at a second set
    assert compiled == list(BOOKS)
