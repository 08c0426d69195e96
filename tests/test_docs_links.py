"""Recorded results live in docs/results/, and every path the pages point at exists (issue 31).

Two kinds of reference are checked in README.md, docs/*.md and docs/results/*.md: Markdown links and
images (`[text](target)`, relative to the page; web addresses and in-page anchors are left alone) and the
repository-root paths the pages quote in prose and commands (`docs/results/NAME`, `docs/figures/...`, with
shell brace lists `{a,b}` expanded).
"""

from __future__ import annotations

import itertools
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), *sorted((ROOT / "docs" / "results").glob("*.md"))]
LINK = re.compile(r"!?\[[^\]\n]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
QUOTED_PATH = re.compile(r"(?<![\w/.-])docs/[\w./{},+-]+")
EXTERNAL = re.compile(r"^(?:[a-z][a-z0-9+.-]*:|#)")  # http:, mailto:, #anchor


def outside_code_blocks(path: Path):
    """(line number, line) of `path` outside its fenced code blocks: a link inside one is not a link."""
    in_block = False
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if line.lstrip().startswith("```"):
            in_block = not in_block
        elif not in_block:
            yield number, line


def expand_braces(text: str) -> list[str]:
    """`a-{x,y}-b` -> [`a-x-b`, `a-y-b`], as a shell would."""
    parts = re.split(r"\{([^{}]*)\}", text)
    choices = [[part] if i % 2 == 0 else part.split(",") for i, part in enumerate(parts)]
    return ["".join(combination) for combination in itertools.product(*choices)]


def test_no_result_json_beside_the_pages():
    assert sorted(p.name for p in (ROOT / "docs").glob("*.json")) == []


def test_every_relative_link_resolves():
    broken = []
    for page in PAGES:
        for number, line in outside_code_blocks(page):
            for target in LINK.findall(line):
                if EXTERNAL.match(target):
                    continue
                if not (page.parent / target.split("#")[0]).exists():
                    broken.append(f"{page.relative_to(ROOT)}:{number}: {target}")
    assert broken == []


def test_every_quoted_docs_path_exists():
    missing = []
    for page in PAGES:
        for number, line in enumerate(page.read_text().splitlines(), start=1):
            for quoted in QUOTED_PATH.findall(line):
                for path in expand_braces(quoted.rstrip(".,")):
                    if not (ROOT / path).exists():
                        missing.append(f"{page.relative_to(ROOT)}:{number}: {path}")
    assert missing == []
