"""A fix answers to its own evidence (issue 27): `lumipose locate` with a map that does not describe the panel
in view refuses with `shape_mismatch` (exit 1) and says by how much; with the right map it still fixes."""

import json

import pytest

from lumipose_cli.main import main
from tests.helpers import PANEL, PANEL_WRONG_RADIUS, TWO_SHAPES, render_panel_frame


@pytest.fixture(scope="module")
def frame(tmp_path_factory):
    folder = tmp_path_factory.mktemp("panel")
    for beacon_map in (PANEL, PANEL_WRONG_RADIUS, TWO_SHAPES):
        (folder / f"{beacon_map.name}.json").write_text(beacon_map.model_dump_json())
    return folder, render_panel_frame(folder)


def _locate(capsys, frame_path, *args) -> tuple[int, dict]:
    code = main(["locate", frame_path, "--json", *args])
    return code, json.loads(capsys.readouterr().out)


def test_the_right_map_still_fixes(frame, capsys):
    folder, path = frame
    code, result = _locate(capsys, path, "--map", str(folder / "panel.json"))
    assert code == 0 and result["ok"]
    assert abs(result["position_m"][0] - 0.1) < 1e-3 and abs(result["position_m"][1] - 0.2) < 1e-3


@pytest.mark.parametrize(
    ("map_args", "beacon"),
    [
        (["--map", "panel-r05.json"], "map beacon 1's shape (0.6 m, corner radius 0.05 m)"),
        ([], "map beacon 0's shape (0.174 m, corner radius 0.02 m)"),  # --map forgotten: the bundled test bench
        (["--map", "two-shapes.json", "--beacon-id", "2"], "map beacon 2's shape (0.3 m, corner radius 0.03 m)"),
    ],
    ids=["wrong-corner-radius", "default-map", "wrong-beacon-of-two"],
)
def test_a_map_that_does_not_describe_the_panel_is_refused(frame, capsys, map_args, beacon):
    folder, path = frame
    map_args = [str(folder / a) if a.endswith(".json") else a for a in map_args]
    code, result = _locate(capsys, path, *map_args)
    assert code == 1 and not result["ok"] and result["reason"] == "shape_mismatch", result
    message = result["message"]
    assert beacon in message and "degrees of freedom" in message and "is its corner radius or size right" in message
    # the people's output says the same
    assert main(["locate", path, *map_args]) == 1
    assert "no fix: shape_mismatch: the panel's corners sit" in capsys.readouterr().out


def test_the_right_beacon_of_two_fixes(frame, capsys):
    folder, path = frame
    code, result = _locate(capsys, path, "--map", str(folder / "two-shapes.json"), "--beacon-id", "1")
    assert code == 0 and result["ok"] and result["beacon_id"] == 1
