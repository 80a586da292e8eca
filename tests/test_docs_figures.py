"""Every figure on the hand-written pages exists and says in its alt text what it shows."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
MIN_ALT = 30  # characters: a phrase that says what the figure shows, not a file name


def pages() -> list[Path]:
    skipped = {"_build", "api", "auto_examples"}
    found = [p for p in sorted(DOCS.rglob("*.md")) if not skipped & set(p.relative_to(DOCS).parts)]
    return [ROOT / "README.md", *found]


def figures(text: str) -> list[tuple[str, str]]:
    """``(alt text, source)`` of every Markdown image in ``text``.

    Parameters
    ----------
    text : str
        A page's source.

    Returns
    -------
    list of tuple of str
        One pair per image.
    """
    return IMAGE.findall(text)


def test_the_parser_finds_images():
    assert figures("x ![tracking error in mrad](a.png) y") == [("tracking error in mrad", "a.png")]
    assert figures("no image: [a link](page.md)") == []


@pytest.mark.parametrize("page", pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_figures_exist_and_have_alt_text(page):
    for alt, src in figures(page.read_text(encoding="utf-8")):
        if src.startswith("http"):
            continue
        assert (page.parent / src).is_file(), f"{page.relative_to(ROOT)}: no file {src}"
        assert len(alt.strip()) >= MIN_ALT, (
            f"{page.relative_to(ROOT)}: {src}'s alt text is too short: {alt!r}"
        )


def test_the_site_has_figures():
    n = sum(len(figures(p.read_text(encoding="utf-8"))) for p in pages() if p.name != "changelog.md")
    assert n >= 6
