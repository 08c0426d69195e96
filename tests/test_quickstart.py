"""docs/quickstart.md followed as written, both paths, from a fresh folder.

The page is read, not copied: every ```bash block's commands run in turn in an empty folder (the checkout's
`samples/` in it, as a clone has it), a ```json block is written to the file the text before it names ("save it
as `NAME`"), and every quoted output block (a bare ``` block after a bash block) must appear, line by line and
in order, in what that block's commands printed: numbers within `TOLERANCE` (times, "... ms", vary with the
machine and are not compared). `lumipose` runs as `main(argv)` in this process (the command a user runs, without
an interpreter start per line), `lumipose serve` as a real service on a free loopback port, to which the page's
`LUMIPOSE_URL` is pointed. Lines that need what only the world has (photos of a printed board, and the profile
made from them) are listed in `NEEDS_THE_WORLD` and said, not skipped silently.

`tests/test_docs_commands.py` checks that each command and flag the docs quote exists.
"""

from __future__ import annotations

import contextlib
import glob
import io
import json
import os
import re
import shlex
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from lumipose_cli.main import main
from shared_schemas import BeaconMap
from simulator.local_server import LocalServer
from simulator.sample_photo import MY_PANEL

ROOT = Path(__file__).resolve().parents[1]
QUICKSTART = ROOT / "docs" / "quickstart.md"
SETUP = "scripts/setup.sh"  # the setup block makes the machine, not the page's steps
# a line that reads these needs the world: 20 photos of a printed board, and the profile calibrated from them
NEEDS_THE_WORLD = ("shots/", "mi8.json")
TOLERANCE = 0.05  # relative, plus 2 in the last printed digit
_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?")
_BLOCK = re.compile(r"^```(\w*)\n(.*?)^```\n", re.S | re.M)


@dataclass
class Block:
    language: str
    text: str
    before: str  # the page's text since the previous block
    path: str  # "researcher" or "integrator": the part of the page it is in


def page_blocks() -> list[Block]:
    text, blocks, start = QUICKSTART.read_text(), [], 0
    for match in _BLOCK.finditer(text):
        before = text[start : match.start()]
        part = re.findall(r"^## (?:A|An) (\w+)", text[: match.start()], re.M)
        blocks.append(Block(match[1], match[2], before, part[-1] if part else "setup"))
        start = match.end()
    return blocks


def same_line(quoted: str, printed: str) -> bool:
    """Whether `printed` is `quoted`: the same words, whole numbers alike, decimals within TOLERANCE (and 2 in
    their last digit); times (a number before "ms") are not compared."""
    quoted, printed = " ".join(quoted.split()), " ".join(printed.split())
    words = _NUMBER.split(quoted)
    if words != _NUMBER.split(printed):
        return False
    for after, a, b in zip(words[1:], _NUMBER.findall(quoted), _NUMBER.findall(printed), strict=True):
        if after.startswith(" ms"):
            continue
        last_digit = 10.0 ** -len(a.partition(".")[2]) if "." in a else 0.0
        if abs(float(a) - float(b)) > (TOLERANCE * abs(float(a)) if last_digit else 0) + 2 * last_digit:
            return False
    return True


def missing_lines(quoted: str, printed: str) -> list[str]:
    """The quoted lines not found, in order, among the printed ones."""
    lines, at, missing = printed.splitlines(), 0, []
    for line in (line for line in quoted.splitlines() if line.strip()):
        found = next((i for i in range(at, len(lines)) if same_line(line, lines[i])), None)
        if found is None:
            missing.append(line)
        else:
            at = found + 1
    return missing


@dataclass
class Reader:
    """A user working down the page in `folder`, with a shell's environment (`export`)."""

    folder: Path
    monkeypatch: pytest.MonkeyPatch
    servers: contextlib.ExitStack
    url: str | None = None
    not_run: list[str] = field(default_factory=list)

    def run_block(self, block: Block) -> str:
        printed = io.StringIO()
        for line in block.text.splitlines():
            command = line.split("  #")[0].split(" # ")[0].strip()
            if not command or command.startswith("#"):
                continue
            if any(needed in command for needed in NEEDS_THE_WORLD):
                self.not_run.append(command)
                continue
            printed.write(self.run(command))
        return printed.getvalue()

    def run(self, command: str) -> str:
        words = shlex.split(command)
        if words[0] == "export":
            for assignment in words[1:]:
                name, _, value = assignment.partition("=")
                if name == "LUMIPOSE_URL":
                    assert self.url is not None, "LUMIPOSE_URL before the page starts a service"
                    value = self.url  # the page's port, here a free one
                self.monkeypatch.setenv(name, value)
            return ""
        assert words[0] == "lumipose", f"the page runs {command!r}: only `lumipose` and `export` are expected"
        # a shell's globbing: sorted, the pattern itself when nothing matches
        argv = [word for pattern in words[1:] for word in (sorted(glob.glob(pattern)) if "*" in pattern else [])
                or [pattern]]
        if argv[0] == "serve":
            return self.serve(argv[1:])
        out = io.StringIO()
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            code = main(argv)
        assert code == 0, f"`{command}` exited {code}:\n{out.getvalue()}"
        return out.getvalue()

    def serve(self, args: list[str]) -> str:
        """The page's `serve`, on a free loopback port (LocalServer's; the page's --host and --port dropped)."""
        kept, skip = [], False
        for word in args:
            if skip:
                skip = False
            elif word in ("--host", "--port"):
                skip = True
            else:
                kept.append(word)
        data_dir = self.folder / kept[kept.index("--data-dir") + 1]
        server = self.servers.enter_context(LocalServer(*kept, "--log-level", "warning", data_dir=data_dir))
        self.url = server.url
        return ""


def follow(path: str, folder: Path, monkeypatch, servers) -> Reader:
    """Every step of one path of the page, each quoted output checked against what its commands printed."""
    reader, printed = Reader(folder, monkeypatch, servers), None
    for block in page_blocks():
        if block.path != path:
            continue
        if block.language == "json":
            names = re.findall(r"save (?:it )?as `([^`]+\.json)`", block.before)
            assert names, f"the page does not say where to save the JSON block:\n{block.text}"
            (folder / names[-1]).write_text(block.text)
        elif block.language == "bash":
            printed = reader.run_block(block)
        elif block.language == "":
            assert printed is not None, f"a quoted output with no command before it:\n{block.text}"
            missing = missing_lines(block.text, printed)
            assert not missing, "the page quotes lines the commands did not print:\n" + "\n".join(missing) + (
                f"\n--- printed:\n{printed}")
            printed = None
    return reader


@pytest.fixture
def fresh_folder(tmp_path, monkeypatch):
    shutil.copytree(ROOT / "samples", tmp_path / "samples")
    monkeypatch.chdir(tmp_path)
    for name in [name for name in os.environ if name.startswith("LUMIPOSE_")]:
        monkeypatch.delenv(name)
    return tmp_path


def test_the_map_the_page_shows_is_the_one_the_sample_photo_was_rendered_for():
    (block,) = [block for block in page_blocks() if block.language == "json" and block.path == "researcher"]
    assert BeaconMap.model_validate(json.loads(block.text)) == MY_PANEL


def test_the_researchers_path_as_written(fresh_folder, monkeypatch):
    with contextlib.ExitStack() as servers:
        reader = follow("researcher", fresh_folder, monkeypatch, servers)
    assert (fresh_folder / "seen.png").stat().st_size > 10_000
    # said, not skipped silently: step 5's calibration from photos of a printed board, and the fix with its profile
    not_run = [line.split()[1:3] for line in reader.not_run]
    assert not_run == [["calibrate", "camera"], ["locate", "samples/panel-photo.jpg"]], reader.not_run


def test_the_integrators_path_as_written(fresh_folder, monkeypatch):
    with contextlib.ExitStack() as servers:
        reader = follow("integrator", fresh_folder, monkeypatch, servers)
        assert reader.url is not None and not reader.not_run
    assert (fresh_folder / "seen.png").stat().st_size > 10_000


def test_quoted_lines_are_compared_by_words_and_numbers():
    assert same_line("position  x=+0.1000 m   (beacon 0)", "position  x=+0.1003 m (beacon 0)")
    assert not same_line("position  x=+0.1000 m   (beacon 0)", "position  x=+0.1200 m (beacon 0)")
    assert not same_line("z=+0.0002 m", "z=-2.3638 m")
    assert same_line("quality   75.8 ms", "quality   1090.1 ms")
    assert not same_line("beacon 17", "beacon 42")
    assert missing_lines("a 1\nc 3", "a 1\nb 2\nc 3") == [] and missing_lines("c 3\na 1", "a 1\nc 3") == ["a 1"]


def test_the_sample_photo_is_a_phone_jpeg_made_by_the_renderer_with_its_truth_beside_it():
    from PIL import Image

    from simulator.sample_photo import sample_photo

    photo, truth_path = ROOT / "samples" / "panel-photo.jpg", ROOT / "samples" / "panel-photo.truth.json"
    assert photo.stat().st_size < 300_000
    with Image.open(photo) as image:
        exif, stored = image.getexif(), image.size
    shot = exif.get_ifd(0x8769)
    assert (exif[0x010F], exif[0x0110], exif[0x0112]) == ("Xiaomi", "MI 8", 6)  # make, model, orientation
    assert float(shot[0x920A]) == 4.22 and stored == (1008, 756) == (shot[0xA002], shot[0xA003])  # landscape rows
    data, truth = sample_photo()  # what `python -m simulator.sample_photo` writes, again
    assert json.loads(truth_path.read_text()) == json.loads(json.dumps(truth))
    with Image.open(io.BytesIO(data)) as again, Image.open(photo) as shipped:
        assert again.size == shipped.size and again.getexif() == shipped.getexif()


def test_a_wrong_truth_file_is_bad_input_naming_it(fresh_folder, capsys):
    (fresh_folder / "pose.json").write_text('{"position_m": [0, 0]}')
    assert main(["locate", "samples/panel-photo.jpg", "--map", "test-bench", "--truth", "pose.json"]) == 2
    assert "pose.json is not a pose (position_m, rotation_wc): position_m" in capsys.readouterr().err
    assert main(["locate", "samples/panel-photo.jpg", "samples/panel-photo.jpg", "--truth",
                 "samples/panel-photo.truth.json"]) == 2
    assert "--truth is one frame's pose" in capsys.readouterr().err


def test_the_measuring_figure_is_drawn_by_its_script(tmp_path):
    import runpy

    assert "](figures/measuring-a-panel.png)" in QUICKSTART.read_text()
    assert (ROOT / "docs" / "figures" / "measuring-a-panel.png").is_file()
    draw = runpy.run_path(str(ROOT / "scripts" / "figure_measuring_a_panel.py"))["draw"]
    draw(tmp_path / "figure.png")
    assert (tmp_path / "figure.png").stat().st_size > 20_000
