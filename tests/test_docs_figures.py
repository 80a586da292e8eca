"""Every figure on the hand-written pages exists and says in its alt text what it shows."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
IMAGE = re.compile(r"!\[([^\]]*)\]\(([^)\s]+)\)")
GALLERY_IMAGE = re.compile(r"auto_examples/images/sphx_glr_(plot_\w+?)_\d{3}\.png$")
MIN_ALT = 30  # characters: a phrase that says what the figure shows, not a file name


def pages() -> list[Path]:
    skipped = {"_build", "api", "auto_examples"}
    found = [p for p in sorted(DOCS.rglob("*.md")) if not skipped & set(p.relative_to(DOCS).parts)]
    return [ROOT / "README.md", *found]


def site_pages() -> list[Path]:
    """The hand-written pages of the site, the changelog (history, not today's figures) left out."""
    return [p for p in pages() if p.parent != ROOT and p.name != "changelog.md"]


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
        made = GALLERY_IMAGE.search(src)
        if made:  # drawn by a gallery example when the site is built: the example must exist
            script = ROOT / "examples" / "gallery" / f"{made.group(1)}.py"
            assert script.is_file(), f"{page.relative_to(ROOT)}: {src} names no gallery example"
        else:
            assert (page.parent / src).is_file(), f"{page.relative_to(ROOT)}: no file {src}"
        assert len(alt.strip()) >= MIN_ALT, (
            f"{page.relative_to(ROOT)}: {src}'s alt text is too short: {alt!r}"
        )


def test_the_site_has_figures():
    n = sum(len(figures(p.read_text(encoding="utf-8"))) for p in pages() if p.name != "changelog.md")
    assert n >= 6


# The built site's figures: counted and checked by docs/_ext/figure_count.py after every HTML build
# with the gallery run (a warning, an error under CI's -W). Its parts are tested here on planted
# pages, so the build's check cannot pass by finding nothing.
sys.path.insert(0, str(DOCS / "_ext"))
import figure_count  # noqa: E402

GOOD = "the 50 ms moving RMS tracking error in mrad against time in s of every controller"


def _site(tmp_path, pages: dict[str, str]) -> Path:
    for rel, body in pages.items():
        path = tmp_path / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"<html><body>{body}</body></html>", encoding="utf-8")
    return tmp_path


def test_the_site_count_reads_images_once_each_and_skips_thumbnails_and_the_changelog(tmp_path):
    site = _site(
        tmp_path,
        {
            "results.html": f'<img src="_images/a.png" alt="{GOOD}"><img src="_images/b.png" alt="short">',
            "per_seed.html": f'<img src="_images/a.png" alt="{GOOD}">',
            "auto_examples/index.html": '<img src="../_images/thumb/sphx_glr_x_thumb.png" alt="x">'
            '<img src="../_images/sphx_glr_plot_y_thumb.png" alt="">',
            "changelog.html": f'<img src="_images/old.png" alt="{GOOD}">',
            "_static/logo.html": '<img src="logo.png" alt="logo">',
        },
    )
    figs = figure_count.site_figures(site)
    assert sorted(figs) == ["a.png", "b.png"]
    assert figs["a.png"] == ("per_seed.html", GOOD)  # the first page in path order


def test_an_alt_text_says_what_it_shows_with_a_unit():
    assert figure_count.says_what_it_shows(GOOD)
    assert figure_count.says_what_it_shows("each controller's error over its floor's: the ratio per segment")
    assert not figure_count.says_what_it_shows("plot ur5 tool swap")  # sphinx-gallery's default
    assert not figure_count.says_what_it_shows("every controller and what it does over the run")  # no unit


def test_the_check_names_a_bad_figure_and_too_few_figures():
    figs = {"a.png": ("results.html", GOOD), "b.png": ("x.html", "plot x")}
    found = figure_count.problems(figs, least=3)
    assert any("b.png" in m and "x.html" in m for m in found)
    assert any("2 figures, fewer than 3" in m for m in found)
    assert figure_count.problems({"a.png": ("results.html", GOOD)}, least=1) == []


def test_the_build_checks_at_least_twenty_figures():
    conf = (DOCS / "conf.py").read_text(encoding="utf-8")
    assert '"figure_count"' in conf
    assert figure_count.MIN_FIGURES >= 20


@pytest.mark.parametrize("page", site_pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_figures_on_the_site_name_their_units(page):
    for alt, src in figures(page.read_text(encoding="utf-8")):
        assert figure_count.says_what_it_shows(alt), (
            f"{page.relative_to(ROOT)}: {src}'s alt text names no unit: {alt!r}"
        )


COMMAND = re.compile(r"`(?:adaptive-dd|python)\s[^`]+`|^\s*(?:\.venv/bin/)?(?:adaptive-dd|python)\s", re.M)


def section_around(lines: list[str], i: int) -> str:
    """The lines of the section (from the heading before line ``i`` to the next) holding line ``i``."""
    start = max((k for k in range(i + 1) if lines[k].startswith("#")), default=0)
    end = min((k for k in range(i + 1, len(lines)) if lines[k].startswith("#")), default=len(lines))
    return "\n".join(lines[start:end])


def test_a_command_is_found_in_the_images_section_only():
    lines = ["# A", "`adaptive-dd benchmark` prints", "# B", "![x](a.png)", "text"]
    assert not COMMAND.search(section_around(lines, 3))
    lines[4] = "```bash\nadaptive-dd predict log.csv\n```"
    assert COMMAND.search(section_around(lines, 3))


def test_every_committed_figure_is_shown_and_names_its_command():
    """A PNG under docs/ is shown on a page, and that page names, in the section that shows it,
    the command that made it."""
    shown: dict[str, list[str]] = {}
    for page in [p for p in pages() if p.parent != ROOT]:  # the changelog's figures too
        lines = page.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            for _, src in figures(line):
                shown.setdefault(Path(src).name, []).append(section_around(lines, i))
    for png in sorted(DOCS.glob("*.png")):
        assert png.name in shown, f"docs/{png.name} is on no page: show it or delete it"
        assert any(COMMAND.search(near) for near in shown[png.name]), (
            f"docs/{png.name}: no page names the command that made it in the section that shows it"
        )
