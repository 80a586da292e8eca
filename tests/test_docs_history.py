"""User pages carry today's state only: no development history outside the changelog.

The documentation's hand-written sources (``docs/**/*.md``, the gallery's scripts and the
README) are scanned for the words of a lab notebook: an issue number, a development round, a
branch, a commit hash, a chain of figures "before -> after". ``docs/changelog.md`` keeps
them. The detector itself is tested first on planted sentences, so the scan over the real pages
cannot pass by matching nothing.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# Generated at build time (ignored by git) or history by design.
SKIPPED_DIRS = {"_build", "api", "auto_examples"}
SKIPPED_FILES = {DOCS / "changelog.md", DOCS / "guide" / "scenario_keys.md"}

_HEX = r"[0-9a-f]{7,40}"
RULES: dict[str, re.Pattern[str]] = {
    "issue number": re.compile(r"\bissues?\s*(?:#\s*)?\d+", re.IGNORECASE),
    "development round": re.compile(
        r"\b(?:this|last|next|previous|earlier|later|that|each|every|one|first|second|third|gate|"
        r"detector|the)\s+round(?:'s)?\b(?!\s+(?:trip|robin|off|up|down|to|half))"
        r"|\bround\s+\d+\b|\brounds\b(?!\s+(?:to|off|up|down))|\bround\s+(?:that|whose|after|before)\b",
        re.IGNORECASE,
    ),
    "branch": re.compile(
        r"\b(?:this|that|the other|another|my|our|a feature)\s+branch(?:'s|es)?\b|\bon\s+main(?:'s)?\b"
        r"|\bmain's\s+code\b|\bbranch\s+kern\b",
        re.IGNORECASE,
    ),
    "commit hash": re.compile(
        rf"\b(?:commit|commits|parent|reverted\s+by|merged?\s+as|cherry-picked)\s*[`(]?(?=[0-9a-f]*[a-f])"
        rf"(?=[0-9a-f]*\d){_HEX}\b|`(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d){_HEX}`",
        re.IGNORECASE,
    ),
    "before -> after chain": re.compile(
        r"(?:\d+\.\d+\s*(?:%|s|ms|x|N m|rad/s)?|\d+\s*(?:%|s|ms|x|N m|rad/s))\s*"
        r"(?:\([^()]{0,40}\)\s*)?(?:->|→)\s*\d+\.\d+"
        r"|\d+(?:\.\d+)?\s*(?:%|s|ms|x)\s*(?:->|→)\s*\d+(?:\.\d+)?\s*(?:%|s|ms|x)\b"
        r"|\bbefore\b[^.\n]{0,30}\d+\.\d+[^.\n]{0,20}\bafter\b[^.\n]{0,20}\d+\.\d+",
        re.IGNORECASE,
    ),
}
# A payload schedule ("0 → 1 → 2.5 → 0 kg") is not a chain: an arrow counts between a decimal
# figure (or one with a unit) and a decimal figure, or between two figures with a unit of time or
# a ratio. Program output
# quoted in a fenced block (the tool's own "before -> after" notes) is today's output, not
# history: the chain rule skips fenced blocks, the other rules do not.
FENCE = re.compile(r"^(```|~~~)")


def user_pages() -> list[Path]:
    """The hand-written sources of the site and the README, changelog excepted."""
    pages = [ROOT / "README.md"]
    for path in sorted(DOCS.rglob("*")):
        if path.suffix not in {".md", ".rst", ".py"} or path in SKIPPED_FILES:
            continue
        if SKIPPED_DIRS & set(path.relative_to(DOCS).parts) or path.parent == DOCS / "_ext":
            continue
        if path.name == "conf.py":
            continue
        pages.append(path)
    pages += sorted((ROOT / "examples" / "gallery").glob("*.py"))
    pages += sorted((ROOT / "examples" / "gallery").glob("*.rst"))
    return pages


def history_hits(text: str) -> list[tuple[int, str, str]]:
    """Return ``(line number, rule, matched text)`` for every history word in ``text``.

    Parameters
    ----------
    text : str
        A page's source.

    Returns
    -------
    list of tuple
        One entry per match, in the order of the page's lines.
    """
    hits = []
    fenced = False
    # Join a paragraph's wrapped lines so a phrase broken across two lines still matches; keep
    # the first line's number.
    for number, line in enumerate(_joined_lines(text), start=1):
        if line is None:
            continue
        if FENCE.match(line.lstrip()):
            fenced = not fenced
            continue
        for rule, pattern in RULES.items():
            if rule == "before -> after chain" and fenced:
                continue
            hits += [(number, rule, m.group(0)) for m in pattern.finditer(line)]
    return hits


def _joined_lines(text: str) -> list[str | None]:
    """Each line followed by the start of the next (so "this\\nround" is seen); None never."""
    lines = text.splitlines()
    out: list[str | None] = []
    for i, line in enumerate(lines):
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if FENCE.match(line.lstrip()) or FENCE.match(nxt.lstrip()):
            out.append(line)
        else:
            out.append(line + " " + " ".join(nxt.split()[:3]))
    return out


PLANTED = [
    ("the gate (issue 28) holds", "issue number"),
    ("as issues #12 and 14 said", "issue number"),
    ("# issue 28's default levels", "issue number"),
    ("measured this round on two cores", "development round"),
    ("the figures of the last\nround were", "development round"),
    ("since round 29 the record", "development round"),
    ("on this branch's final code", "branch"),
    ("run on main's code", "branch"),
    ("on the code of commit `e1dbf4d` (24 November)", "commit hash"),
    ("(commit 0af4897, reverted by d5d46b7)", "commit hash"),
    ("the parent commit (28e11f3)", "commit hash"),
    ("2.010 (max 4.99) -> 1.040 (max 1.28)", "before -> after chain"),
    ("a cold run 307 s -> 291 s", "before -> after chain"),
    ("1.24 -> 1.16", "before -> after chain"),
    ("1.24 → 1.16 on the UR5", "before -> after chain"),
]
CLEAN = [
    "0 → 3 → 1 → 0 kg payloads",
    "0 → 1 → 2.5 → 0 kg",
    "rounded to 3 decimals; a round trip",
    "`df.round(2)` prints the table",
    "a branch on `closed_forms is None` in the law",
    "the ratio 1.279 (max 1.43) of the 3 kg segment",
    "hash 0123456789 of the source",
    "```\nprincipal moments 0.00155 -> 0.00167 kg m^2\n```",
]


@pytest.mark.parametrize(("text", "rule"), PLANTED)
def test_detector_finds_planted_history(text, rule):
    assert rule in {r for _, r, _ in history_hits(text)}, text


@pytest.mark.parametrize("text", CLEAN)
def test_detector_leaves_todays_facts(text):
    assert history_hits(text) == []


def test_pages_are_found():
    names = {p.relative_to(ROOT).as_posix() for p in user_pages()}
    assert {"README.md", "docs/index.md", "docs/getting_started.md", "docs/limits.md"} <= names
    assert "docs/changelog.md" not in names


@pytest.mark.parametrize("page", user_pages(), ids=lambda p: p.relative_to(ROOT).as_posix())
def test_user_page_has_no_history(page):
    hits = history_hits(page.read_text(encoding="utf-8"))
    listed = "\n".join(f"  {page.relative_to(ROOT)}:{n}: {rule}: {text!r}" for n, rule, text in hits)
    assert not hits, (
        f"development history on a user page (move it to docs/changelog.md, keep today's "
        f"figure with the command that prints it):\n{listed}"
    )
