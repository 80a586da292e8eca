"""The figures of the built site: counted, each with its alt text, after every HTML build.

A figure is an ``<img>`` on a page of the site (the changelog, the gallery's thumbnails and the
theme's own images left out), counted once however many pages show it. It *says what it shows*
when its alt text is at least :data:`MIN_ALT` characters long and names a unit (``[mrad]``, ``kg``,
``ms``, ...) or a dimensionless quantity (a ratio, standard deviations). After an HTML build
with the gallery run, the extension warns (an error under ``-W``) when a figure does not, or
when the site has fewer than :data:`MIN_FIGURES`. From the repository's root, on a built site::

    python docs/_ext/figure_count.py docs/_build/html

prints every figure (file, first page, alt text) and the count.
"""

from __future__ import annotations

import re
import sys
from html.parser import HTMLParser
from pathlib import Path

MIN_FIGURES = 20
"""The site's figures, at least."""
MIN_ALT = 30
"""Characters of alt text, at least: a phrase that says what the figure shows, not a file name."""
SKIPPED_PAGES = ("changelog.html", "genindex.html", "search.html", "py-modindex.html")
UNIT = re.compile(
    r"\[[^\]]+\]|\b(?:mrad|rad/s|rad|kg m\^?2|kg m²|kg|N m|mm|ms|s|Hz)\b|%|\bratios?\b"
    r"|\bstandard deviations?\b",
)
"""A unit, or a quantity without one, in an alt text."""
THUMBNAIL = re.compile(r"/thumb/|_thumb\.\w+$")
"""The gallery's thumbnails: links to its pages, not figures."""


class _Images(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.found: list[tuple[str, str]] = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            a = dict(attrs)
            self.found.append((a.get("src") or "", a.get("alt") or ""))


def page_images(html: str) -> list[tuple[str, str]]:
    """``(src, alt)`` of every content image of one HTML page.

    Parameters
    ----------
    html : str
        The page's HTML.

    Returns
    -------
    list of tuple of str
        One pair per ``<img>``, the gallery's thumbnails (``/thumb/`` in their path, or a name
        ending ``_thumb``) and inline data left out.
    """
    parser = _Images()
    parser.feed(html)
    return [(s, a) for s, a in parser.found if s and not THUMBNAIL.search(s) and not s.startswith("data:")]


def site_figures(html_dir: str | Path) -> dict[str, tuple[str, str]]:
    """Every figure of a built site, by file name: ``{name: (first page, alt text)}``.

    Parameters
    ----------
    html_dir : str or Path
        The HTML builder's output folder.

    Returns
    -------
    dict
        One entry per image file shown on some page (the changelog and the theme's static files
        left out), its first page in path order and the longest alt text it is shown with.
    """
    root = Path(html_dir)
    found: dict[str, tuple[str, str]] = {}
    for page in sorted(root.rglob("*.html")):
        rel = page.relative_to(root).as_posix()
        if rel.startswith(("_static/", "_sources/", "_modules/")) or page.name in SKIPPED_PAGES:
            continue
        for src, alt in page_images(page.read_text(encoding="utf-8")):
            if "_static/" in src:
                continue
            name = src.rsplit("/", 1)[-1]
            old = found.get(name)
            if old is None or len(alt) > len(old[1]):
                found[name] = (old[0] if old else rel, alt)
    return found


def says_what_it_shows(alt: str) -> bool:
    """Whether an alt text is long enough and names a unit or a dimensionless quantity.

    Parameters
    ----------
    alt : str
        A figure's alt text.

    Returns
    -------
    bool
        True if it has at least :data:`MIN_ALT` characters and a unit.

    Examples
    --------
    >>> says_what_it_shows("tracking error in mrad against time in s, every controller")
    True
    >>> says_what_it_shows("plot ur5 tool swap")
    False
    """
    return len(alt.strip()) >= MIN_ALT and UNIT.search(alt) is not None


def problems(figures: dict[str, tuple[str, str]], least: int = MIN_FIGURES) -> list[str]:
    """What the site's figures lack: alt text with a unit, or their number.

    Parameters
    ----------
    figures : dict
        What :func:`site_figures` returns.
    least : int
        The figures the site must have.

    Returns
    -------
    list of str
        One message per figure without a good alt text, and one if there are fewer than
        ``least`` figures; empty when all is well.
    """
    out = [
        f"{page}: figure {name} has no alt text saying what it shows, with units: {alt!r}"
        for name, (page, alt) in figures.items()
        if not says_what_it_shows(alt)
    ]
    if len(figures) < least:
        out.append(f"the site has {len(figures)} figures, fewer than {least}")
    return out


def _check(app, exception) -> None:
    if exception is not None or app.builder.format != "html":
        return
    from sphinx.util import logging

    log = logging.getLogger(__name__)
    figures = site_figures(app.outdir)
    if str(app.config.plot_gallery).strip().lower() not in ("true", "1", "yes"):
        log.info(f"figure count: {len(figures)} (the gallery not run: not checked)")
        return
    log.info(f"figure count: {len(figures)} figures on the site")
    for message in problems(figures):
        log.warning(message)


def setup(app):
    app.connect("build-finished", _check)
    return {"parallel_read_safe": True, "parallel_write_safe": True}


if __name__ == "__main__":
    figs = site_figures(sys.argv[1] if len(sys.argv) > 1 else "docs/_build/html")
    for name, (page, alt) in sorted(figs.items(), key=lambda kv: kv[1][0]):
        mark = " " if says_what_it_shows(alt) else "!"
        print(f"{mark} {page:45s} {name:50s} {alt[:90]}")
    print(
        f"{len(figs)} figures, {sum(says_what_it_shows(a) for _, a in figs.values())} with alt text and units"
    )
