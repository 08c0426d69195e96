"""A fix physically odd for its map is warned (server.plausibility): docs/quickstart.md's step 3, where a frame of
the bundled 0.174 m panel located with a map that says 0.6 m put the camera 3.4 m below the panel, silently."""

import json

from lumipose_cli.main import main
from server.plausibility import odd_fix_warning
from shared_schemas import BeaconMap, LocateResult

MY_PANEL = {"schema": "lumipose.map/1", "name": "my-panel",
            "beacons": [{"id": 0, "center_m": [0.0, 0.0, 1.0], "side_m": 0.6, "corner_radius_m": 0.01}]}


def test_a_panel_too_large_in_the_map_is_warned_with_the_size_to_check(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my-panel.json").write_text(json.dumps(MY_PANEL))
    assert main(["render", "shot", "--position", "0.1", "0.2", "0", "--ypr", "5", "2", "-1", "--scale", "0.25"]) == 0
    capsys.readouterr()
    assert main(["locate", "shot.json", "--map", "my-panel.json"]) == 0
    out = capsys.readouterr().out
    assert "z=-2.3978 m" in out  # 3.45 times as far as the camera is: 0.6 / 0.174
    assert ("warning   the camera is 2.40 m below the map's z = 0, 3.48 m from panel 0 that the map hangs 1.00 m "
            "above it: a fix's distance scales with the panel's size, so check side_m (0.6 m)") in out
    assert main(["locate", "shot.json"]) == 0  # the panel it shows: no warning
    assert "below the map's z = 0" not in capsys.readouterr().out


def fix_at(z_m: float, beacon_z_m: float = 1.0) -> tuple[LocateResult, BeaconMap]:
    beacon_map = BeaconMap.model_validate({**MY_PANEL, "beacons": [{"id": 0, "center_m": [0, 0, beacon_z_m],
                                                                    "side_m": 0.6}]})
    result = LocateResult(ok=True, position_m=[0.0, 0.0, z_m], beacon_id=0, timing_ms={"total": 1.0})
    return result, beacon_map


def test_a_camera_somewhat_below_zero_or_under_a_map_at_zero_is_not_warned():
    assert odd_fix_warning(*fix_at(-0.3)) is None  # the demo bench's camera held 0.3 m under its grid: a good fix
    assert odd_fix_warning(*fix_at(-0.95)) is None  # a phone near the floor under a z = 0 taken at the hand
    assert odd_fix_warning(*fix_at(-1.05)) is not None  # farther below z = 0 than the panel hangs above it
    assert odd_fix_warning(*fix_at(-2.0, beacon_z_m=0.0)) is None  # the map's z = 0 is its ceiling: nothing to say
