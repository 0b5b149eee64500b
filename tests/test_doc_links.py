"""Every relative link of README.md and docs/*.md resolves (issue #53: the README's
measured tables moved to docs/accuracy.md and docs/performance.md, each section that
left it linked): the file exists, and a ``#fragment`` into a Markdown file names one of
its headings, as GitHub makes their anchors."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def prose(text: str) -> str:
    """``text`` without fenced blocks and inline code (a link there is not a link)."""
    return re.sub(r"`[^`\n]*`", "", re.sub(r"```.*?```", "", text, flags=re.S))


def github_anchor(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation but ``-`` and ``_`` dropped,
    spaces to ``-`` ("The device in a circuit simulator: `--spice`" ->
    "the-device-in-a-circuit-simulator---spice")."""
    text = re.sub(r"[`*]", "", heading.strip()).lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    found, seen = set(), {}
    text = re.sub(r"```.*?```", "", page.read_text(), flags=re.S)
    for match in re.finditer(r"^#{1,6}\s+(.*)$", text, re.M):
        anchor = github_anchor(match.group(1))
        n = seen.get(anchor, 0)
        seen[anchor] = n + 1
        found.add(anchor if n == 0 else f"{anchor}-{n}")
    return found


def links(page: Path) -> list[str]:
    return [t for t in re.findall(r"\]\(([^)\s]+)\)", prose(page.read_text()))
            if not re.match(r"[a-z][a-z0-9+.-]*:", t)]


def test_the_anchor_rule():
    assert github_anchor("The device in a circuit simulator: `--spice`") == \
        "the-device-in-a-circuit-simulator---spice"
    assert github_anchor("Accuracy and speed (measured)") == "accuracy-and-speed-measured"
    assert github_anchor("Against the paper's bench") == "against-the-papers-bench"


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_every_relative_link_resolves(page):
    broken = []
    for target in links(page):
        path, _, fragment = target.partition("#")
        linked = (page.parent / path) if path else page
        if not linked.exists():
            broken.append(f"{target}: no such file")
        elif fragment and linked.suffix == ".md" and fragment not in anchors(linked):
            broken.append(f"{target}: no heading with that anchor")
    assert not broken, f"{page.relative_to(ROOT)}: {broken}"


def test_the_readme_links_the_measured_pages():
    """The tables that left the README are one link away."""
    readme_links = {t.partition("#")[0] for t in links(ROOT / "README.md")}
    assert {"docs/accuracy.md", "docs/performance.md", "docs/commands.md",
            "docs/scene_files.md"} <= readme_links
