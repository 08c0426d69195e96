"""Scenes rendered as the app captures them: `lumipose simulate --bursts` (simulator/bursts.py)."""

import json

import numpy as np
import pytest

from lumipose_cli.main import main
from server.ingest import read_fixture
from server.vlc.capture import ID_BRIGHTNESS_FRACTION, ID_BURST_FRAMES, ID_EXPOSURE_S, id_frame_interval_s
from simulator.bursts import ID_GAP_S, burst_scenes, capture_starts
from simulator.scene import find_scene

KINDS = ["pose"] + ["id"] * ID_BURST_FRAMES


def written(folder):
    """(stem, metadata) of every fixture in `folder` (not scene.json, map.json), in name order."""
    return [(path.stem, json.loads(path.read_text())) for path in sorted(folder.glob("*_*.json"))]


def test_bursts_are_written_in_capture_order_with_each_frame_s_own_timing(tmp_path):
    office = find_scene("office")
    assert (
        main(["simulate", "office", str(tmp_path), "--bursts", "--limit", "2", "--scale", "0.1", "--workers", "1"]) == 0
    )
    frames = written(tmp_path)
    assert [meta["frame_kind"] for _, meta in frames] == KINDS * 2
    assert frames[0][0] == "office_0000_0_pose" and frames[1][0] == "office_0000_1_id"
    stamps = [meta["timestamp_ns"] for _, meta in frames]
    assert stamps == sorted(stamps) and len(set(stamps)) == len(stamps)
    pose, ids = frames[0][1], [meta for _, meta in frames[1:5]]
    # the pose frame with the scene's own sensor, the ID frames with its id_frames settings
    assert pose["exposure_s"] == office.sensor.exposure_s and pose["iso"] == office.sensor.iso
    assert all(m["exposure_s"] == office.id_frames.exposure_s and m["iso"] == office.id_frames.iso for m in ids)
    assert all(m["rolling_shutter_skew_s"] == office.sensor.rolling_shutter_skew_s for m in ids)
    # the first ID frame right after the pose frame's exposure, then a quarter message apart
    first = pose["timestamp_ns"] + round((office.sensor.exposure_s + ID_GAP_S) * 1e9)
    assert ids[0]["timestamp_ns"] == pytest.approx(first, abs=1)
    assert np.diff([m["timestamp_ns"] for m in ids]) == pytest.approx(id_frame_interval_s() * 1e9, abs=1)
    # --scale keeps the ID frames' size relative to the pose frames' (office: half)
    assert ids[0]["width"] == pytest.approx(pose["width"] * office.id_frames.scale / office.camera.scale, abs=1)
    for stem, _ in frames:
        read_fixture(tmp_path / f"{stem}.json")  # the server reads every one


def test_a_single_pose_as_a_burst_of_a_scene_without_id_settings(tmp_path):
    bench = find_scene("paper-bench")
    assert (
        main(
            [
                "simulate",
                "paper-bench",
                str(tmp_path),
                "--bursts",
                "--pose",
                "0.1",
                "0.2",
                "0",
                "--scale",
                "0.1",
                "--workers",
                "1",
            ]
        )
        == 0
    )
    frames = written(tmp_path)
    assert [meta["frame_kind"] for _, meta in frames] == KINDS
    pose, first_id = frames[0][1], frames[1][1]
    assert pose["exposure_s"] == bench.sensor.exposure_s == 0.01
    assert first_id["exposure_s"] == ID_EXPOSURE_S
    # the ISO the phone would raise to: a fixed share of the pose frame's exposure x ISO
    assert first_id["iso"] * first_id["exposure_s"] == pytest.approx(
        pose["iso"] * pose["exposure_s"] * ID_BRIGHTNESS_FRACTION
    )
    assert all(m["ground_truth"]["position_m"] == pytest.approx([0.1, 0.2, 0.0]) for _, m in frames)


def test_captures_that_would_overlap_start_after_the_one_before():
    span = 0.15
    assert capture_starts([0.0, 0.0, 0.0], span) == pytest.approx([0.0, span + ID_GAP_S, 2 * (span + ID_GAP_S)])
    assert capture_starts([0.0, 0.5, 0.6], span) == pytest.approx([0.0, 0.5, 0.5 + span + ID_GAP_S])


def test_the_id_scene_differs_from_the_pose_scene_only_in_its_exposure_iso_and_size():
    pose_scene, id_scene = burst_scenes(find_scene("office"))
    assert pose_scene == find_scene("office")
    assert id_scene.sensor.model_dump(exclude={"exposure_s", "iso"}) == pose_scene.sensor.model_dump(
        exclude={"exposure_s", "iso"}
    )
    assert id_scene.camera.scale == pose_scene.id_frames.scale and id_scene.beacons == pose_scene.beacons
