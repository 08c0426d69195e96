"""Every `lumipose ...` command and flag quoted in README.md and docs/*.md exists (issue 15).

The docs' command lines are read as they are written: code blocks (with `\\` continuations) and inline
`lumipose ...` code spans; `[--x X]` optional parts; placeholders (FRAME, DIR, FRAMES..., ...); `a|b|c`
alternative commands, each checked with the flags that follow; ` | ` between two synopsis branches
(`lumipose client locate FRAME | samples store|list`) when the next word is a command of the same tree,
else a shell pipe that ends the command. Each is checked against the argparse tree built in-process.
"""

from __future__ import annotations

import argparse
import re
import shlex
from dataclasses import dataclass
from pathlib import Path

import pytest

from lumipose_cli.main import build_parser

ROOT = Path(__file__).resolve().parent.parent
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
SHELL_OPERATORS = {"|", "||", "&&", ";", "&", ">", ">>", "<", "2>&1", "2>", "$(", ")"}
VALUE = re.compile(r"-\d")  # a negative number or cell label (-8,11) is a value, not a flag


@dataclass(frozen=True)
class Quote:
    file: str
    line: int
    text: str


def quoted_command_lines(path: Path) -> list[Quote]:
    """The lines of `path`'s code blocks, continuations joined, and its inline code spans that start with
    `lumipose`."""
    quotes, in_block, pending, pending_line = [], False, "", 0
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if line.lstrip().startswith("```"):
            in_block, pending = not in_block, ""
            continue
        if in_block:
            if line.lstrip().startswith("| ") and not pending and quotes:  # a synopsis' next branch
                quotes[-1] = Quote(path.name, quotes[-1].line, f"{quotes[-1].text} {line.strip()}")
                continue
            if not pending:
                pending_line = number
            pending += line.rstrip()
            if pending.endswith("\\"):
                pending = pending[:-1] + " "
                continue
            quotes.append(Quote(path.name, pending_line, pending))
            pending = ""
        else:
            quotes += [Quote(path.name, number, span) for span in re.findall(r"`([^`\n]+)`", line)
                       if span.split()[0].endswith("lumipose")]
    return quotes


def _tokens(text: str) -> list[str]:
    text = re.sub(r"(^|\s)#.*", "", text)  # a shell comment
    try:
        return shlex.split(text)
    except ValueError:  # an apostrophe in prose
        return text.split()


def _is_start(tokens: list[str], i: int) -> bool:
    word, before = tokens[i], tokens[i - 1] if i > 0 else ""
    if word == "lumipose_cli":
        return before == "-m"
    return word.rsplit("/", 1)[-1] == "lumipose" and not before.startswith("-")  # not `docker build -t lumipose`


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _values_taken(action: argparse.Action) -> int | None:
    """How many words a flag takes: a count, or None for 'all until the next flag'."""
    if action.nargs is None:
        return 0 if isinstance(action, argparse._StoreConstAction | argparse._StoreTrueAction) else 1
    if isinstance(action.nargs, int):
        return action.nargs
    return None if action.nargs in ("+", "*") else 1


def _clean(word: str) -> str:
    return word.strip("[]")


def check_command(words: list[str], path: list[str], tree: dict[str, argparse.ArgumentParser]) -> list[str]:
    """Problems with `words` (what follows `lumipose`), walking the parser tree from `path`."""
    parser = tree[" ".join(path)]
    i = 0
    while i < len(words):
        word = _clean(words[i])
        i += 1
        if not word or word == "..." or word.endswith("..."):
            continue
        if word in SHELL_OPERATORS:
            if word != "|" or i >= len(words):
                return []
            # a synopsis branch (`... | samples store`) when the next word is a command here or above; else a pipe
            following = _clean(words[i]).split("|")[0]
            for depth in range(len(path), 0, -1):
                if following in _subcommands(tree[" ".join(path[:depth])]):
                    return check_command(words[i:], path[:depth], tree)
            return []
        if word.startswith("-") and not VALUE.match(word):
            problems = []
            action = None
            for flag in word.split("|"):
                flag = flag.split("=")[0]
                action = parser._option_string_actions.get(flag)
                if action is None:
                    problems.append(f"no flag {flag} on `{' '.join(path)}`")
            if problems:
                return problems
            taken = _values_taken(action) if action is not None and "=" not in word else 0
            while i < len(words) and (taken is None or taken > 0):
                value = _clean(words[i])
                if value in SHELL_OPERATORS or (value.startswith("-") and not VALUE.match(value)):
                    break
                i += 1
                if taken is not None:
                    taken -= 1
            continue
        commands = _subcommands(parser)
        if not commands:
            continue  # a positional argument of a leaf command
        alternatives = word.split("|")
        if all(name in commands for name in alternatives):
            return [problem for name in alternatives for problem in check_command(words[i:], [*path, name], tree)]
        if re.fullmatch(r"[A-Z][A-Z0-9_.]*|<[^>]+>", word):
            return []  # a placeholder for a command (`lumipose client ACTION`)
        unknown = ", ".join(name for name in alternatives if name not in commands)
        return [f"no command `{unknown}` in `{' '.join(path)}` (it has {', '.join(commands)})"]
    return []


def parser_tree() -> dict[str, argparse.ArgumentParser]:
    """Every parser of `lumipose` by its command path ("lumipose bench grid")."""
    tree: dict[str, argparse.ArgumentParser] = {}

    def visit(parser: argparse.ArgumentParser, path: str) -> None:
        tree[path] = parser
        for name, sub in _subcommands(parser).items():
            visit(sub, f"{path} {name}")

    visit(build_parser(), "lumipose")
    return tree


def problems_in(quotes: list[Quote], tree: dict[str, argparse.ArgumentParser]) -> list[str]:
    problems = []
    for quote in quotes:
        tokens = _tokens(quote.text)
        for i in range(len(tokens)):
            if _is_start(tokens, i):
                for problem in check_command(tokens[i + 1 :], ["lumipose"], tree):
                    problems.append(f"{quote.file}:{quote.line}: {problem}   in: {quote.text.strip()}")
    return problems


@pytest.fixture(scope="module")
def tree() -> dict[str, argparse.ArgumentParser]:
    return parser_tree()


def test_every_documented_command_and_flag_exists(tree):
    quotes = [quote for path in DOCS for quote in quoted_command_lines(path)]
    assert len([q for q in quotes if "lumipose " in q.text]) > 50  # the docs were read
    problems = problems_in(quotes, tree)
    assert not problems, "commands or flags in the docs that `lumipose` does not have:\n" + "\n".join(problems)


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        ("lumipose bench grid|render [--figures DIR] [--json]", ["no flag --figures on `lumipose bench render`"]),
        ("lumipose bench grid --limit 20 --nope", ["no flag --nope on `lumipose bench grid`"]),
        ("lumipose client [--url URL] locate FRAME | samples store|list | maps list|get", []),
        ("lumipose client locate FRAME | maps frobnicate", ["no command `frobnicate` in `lumipose client maps`"]),
        ("lumipose locate FRAME --json | head -3", []),
        ("lumipose render out/f --position 0.1 0.2 0 --ypr 5 2 -1 --scale 0.25  # a comment --nope", []),
        ("PYTHONPATH=. python -m lumipose_cli survey FRAMES... --map SKETCH --anchor ID --out MAP", []),
        ("lumipose benchmark grid", ["no command `benchmark` in `lumipose`"]),
        ("lumipose calibrate board --out board.pdf | camera PHOTOS... --board b.json --bored x",
         ["no flag --bored on `lumipose calibrate camera`"]),
    ],
)
def test_the_docs_reader_understands_how_the_docs_write_commands(tree, line, expected):
    found = problems_in([Quote("doc.md", 7, line)], tree)
    assert len(found) == len(expected), found
    for problem, start in zip(found, expected, strict=True):
        assert problem.startswith(f"doc.md:7: {start}"), problem


def test_a_code_block_line_and_its_continuation_are_one_command(tmp_path):
    doc = tmp_path / "doc.md"
    doc.write_text("text `lumipose fov --nope` and `other`\n```bash\nlumipose bench grid \\\n  --limit 3\n```\n")
    quotes = quoted_command_lines(doc)
    assert [(q.line, q.text.split()) for q in quotes] == [
        (1, ["lumipose", "fov", "--nope"]),
        (3, ["lumipose", "bench", "grid", "--limit", "3"]),
    ]
