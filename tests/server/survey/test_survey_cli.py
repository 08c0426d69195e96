"""`lumipose survey`: recorded frames in, a map out; exit 1 for a set that cannot give it, 2 for bad input."""

from __future__ import annotations

import glob
import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

from lumipose_cli.main import main
from shared_schemas import load_map
from shared_schemas.survey import SurveyReport
from simulator.survey import write_survey_fixtures
from tests.helpers import survey_set


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """The quarter-scale office set written as fixtures, with its labels and sketch."""
    truth, sketch, anchor, shots = survey_set()
    frames, labels, sketch_path = write_survey_fixtures(tmp_path_factory.mktemp("survey"), list(shots), sketch)
    return truth, anchor, frames, labels, sketch_path


def _survey(*args: str) -> int:
    return main(["survey", *map(str, args)])


def test_the_map_is_written_and_every_panel_printed(recorded, tmp_path, capsys):
    truth, anchor, frames, labels, sketch = recorded
    out = tmp_path / "office-surveyed.json"
    assert _survey(*frames, "--map", sketch, "--anchor", anchor, "--labels", labels, "--out", out) == 0
    printed = capsys.readouterr().out
    surveyed = load_map(out)
    assert surveyed.name == "office-surveyed" and surveyed.bearing_deg is not None
    for beacon in truth.beacons:
        assert np.linalg.norm(np.subtract(surveyed.beacon(beacon.id).center_m, beacon.center_m)) < 0.004
        assert f"\n{beacon.id:>6}  " in printed
    assert "used" in printed and "bearing" in printed and f"written to {out}" in printed


def test_json_prints_the_report(recorded, tmp_path, capsys):
    _, anchor, frames, labels, sketch = recorded
    out = tmp_path / "map.json"
    args = (*frames, "--map", sketch, "--anchor", anchor, "--labels", labels, "--out", out, "--name", "room-1")
    assert _survey(*args, "--json") == 0
    report = SurveyReport.model_validate_json(capsys.readouterr().out)
    assert report.map.name == "room-1" and report.map == load_map(out)
    assert report.frames_used + len(report.skipped) == len(frames) and len(report.beacons) == 4


def test_frames_that_see_one_panel_only_are_refused_with_exit_1(recorded, tmp_path, capsys):
    _, anchor, frames, labels, sketch = recorded
    given = json.loads(labels.read_text())
    single = tmp_path / "single.json"
    single.write_text(json.dumps({name: found[:1] for name, found in given.items()}))
    out = tmp_path / "map.json"
    assert _survey(*frames[:3], "--map", sketch, "--anchor", anchor, "--labels", single, "--out", out) == 1
    error = capsys.readouterr().err
    assert "refused: no frame sees two named panels" in error and "a survey frame must see two or more" in error
    assert not out.exists()


def test_a_panel_left_unconnected_is_refused_naming_it(recorded, tmp_path, capsys):
    _, anchor, frames, labels, sketch = recorded
    given = json.loads(labels.read_text())
    without = tmp_path / "without_99.json"
    without.write_text(json.dumps({name: [x for x in found if x["beacon_id"] != 99] for name, found in given.items()}))
    args = (*frames, "--map", sketch, "--anchor", anchor, "--labels", without, "--out", tmp_path / "map.json")
    assert _survey(*args) == 1
    assert "beacon 99 is not connected to anchor 17" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ({"anchor": "7"}, "anchor 7 is not in sketch"),
        ({"labels": {"frame_00.json": [{"beacon_id": 5, "x_px": 1, "y_px": 1}]}}, "names beacon 5, which is not in"),
        ({"labels": {"frame_99.json": []}}, "its keys name none of the frames given"),
        ({"labels": "not json"}, "cannot read labels"),
        ({"frame": "missing.json"}, "missing.json"),
        ({"name": "no spaces"}, "map name 'no spaces' must match"),
    ],
)
def test_bad_input_exits_2_naming_it(recorded, tmp_path, capsys, change, expected):
    _, anchor, frames, labels, sketch = recorded
    if "labels" in change:
        labels = tmp_path / "labels.json"
        labels.write_text(change["labels"] if isinstance(change["labels"], str) else json.dumps(change["labels"]))
    given = [*frames[:2], tmp_path / change["frame"]] if "frame" in change else frames[:2]
    args = [*given, "--map", sketch, "--anchor", change.get("anchor", anchor), "--labels", labels]
    args += ["--out", tmp_path / "map.json", *(["--name", change["name"]] if "name" in change else [])]
    assert _survey(*args) == 2
    assert expected in capsys.readouterr().err


QUICKSTART = Path(__file__).resolve().parents[3] / "docs" / "quickstart.md"
NUMBER = re.compile(r"[-+]?\d+(?:\.(\d+))?")


def _step_5() -> tuple[list[str], list[str]]:
    """The integrator's step 5 of docs/quickstart.md: its commands and the output it quotes."""
    step = QUICKSTART.read_text().split("**5. Survey the room**", 1)[1].split("**6.", 1)[0]
    commands, output = re.findall(r"```(?:bash)?\n(.*?)```", step, re.S)
    return [line for line in commands.splitlines() if line.strip()], output.splitlines()


def _same_but_numbers(printed: str, quoted: str) -> bool:
    """The same text, each number within two units of its last quoted digit."""
    if NUMBER.sub("#", printed) != NUMBER.sub("#", quoted):
        return False
    pairs = zip(NUMBER.finditer(printed), NUMBER.finditer(quoted), strict=True)
    return all(abs(float(p[0]) - float(q[0])) <= 2 * 10.0 ** -len(q[1] or "") + 1e-9 for p, q in pairs)


def test_the_quickstarts_survey_step_runs_as_written_and_prints_what_it_quotes(tmp_path, capsys, monkeypatch):
    """From an empty folder, step 5's commands as the page writes them (the shell's glob expanded; the
    `client` lines need the service of step 2: tests/test_quickstart.py): the simulated set is written
    where the survey reads it, the survey writes room.json, and both print the page's lines."""
    monkeypatch.chdir(tmp_path)
    commands, quoted = _step_5()
    local = [shlex.split(line) for line in commands if not line.startswith("lumipose client")]
    assert [argv[:2] for argv in local] == [["lumipose", "simulate"], ["lumipose", "survey"]]
    for argv in local:
        expanded = [match for arg in argv[1:] for match in (sorted(glob.glob(arg)) if "*" in arg else [arg])]
        assert main(expanded) == 0, argv
    printed = capsys.readouterr().out.splitlines()
    assert len(printed) == len(quoted)
    for line, quote in zip(printed, quoted, strict=True):
        assert _same_but_numbers(line, quote), (line, quote)
    assert load_map("room.json").name == "room" and load_map("out/survey/map.json").beacon(17) is not None
