"""Series of samples: the paper's grid, rotation variation, fixtures on disk, the CLI."""

import json

import numpy as np
import pytest

from lumipose_cli.main import main
from server.ingest import read_fixture
from simulator.sampling import render_pose, series_poses, write_series
from simulator.scene import Scene, find_scene


def small_bench(**series) -> Scene:
    bench = find_scene("paper-bench")
    scene = bench.model_copy(update={"camera": bench.camera.model_copy(update={"scale": 0.1})})
    if series:
        scene = Scene.model_validate({**scene.model_dump(by_alias=True), "series": series})
    return scene


def test_paper_grid_has_391_points_in_the_papers_order():
    poses = series_poses(find_scene("paper-bench"))
    assert len(poses) == 391
    assert (poses[0].label, poses[0].position_m) == ("-8,11", (-0.4, 0.55, 0.0))
    assert (poses[-1].label, poses[-1].position_m) == ("8,-11", (0.4, -0.55, 0.0))
    assert all(p.ypr_deg == (0.0, 0.0, 0.0) for p in poses)  # face to face


def test_rotation_variation_is_bounded_and_deterministic():
    series = {"path": {"kind": "grid", "x_m": [-0.1, 0.1, 0.05], "y_m": [-0.1, 0.1, 0.05]},
              "rotation": {"yaw_deg": 5.0, "max_tilt_deg": 3.0, "yaw_jitter_deg": 2.0}}
    poses = series_poses(small_bench(**series))
    assert len(poses) == 25 and poses[0].label == "-2,2" and poses[0].position_m[:2] == (-0.1, 0.1)
    ypr = np.array([p.ypr_deg for p in poses])
    assert np.all(np.abs(ypr[:, 0] - 5.0) <= 2.0) and np.all(np.hypot(ypr[:, 1], ypr[:, 2]) <= 3.0)
    assert np.ptp(ypr[:, 1]) > 1.0  # really drawn
    assert series_poses(small_bench(**series)) == poses


def test_walk_series_has_times_and_shake():
    series = {"path": {"kind": "spiral", "area_m": [-0.5, -0.5, 0.5, 0.5], "spacing_m": 0.25, "speed_mps": 1.0,
                       "frame_interval_s": 0.25, "height_m": 0.2},
              "rotation": {"shake_deg": 1.0, "face_walking_direction": True}}
    poses = series_poses(small_bench(**series))
    assert [p.t_s for p in poses[:3]] == [0.0, 0.25, 0.5]
    assert poses[0].position_m == (-0.5, -0.5, 0.2)
    yaw = np.array([p.ypr_deg[0] for p in poses])
    assert abs(yaw[0]) < 4 and abs(yaw[6] - 90) < 4  # east first, then north (plus shake)


def test_write_series_makes_fixtures_that_reproduce(tmp_path):
    scene = small_bench(path={"kind": "poses", "poses": [
        {"position_m": [0.05, 0.0, 0.0]}, {"position_m": [-0.1, 0.1, 0.0], "ypr_deg": [10.0, 2.0, 0.0]}]})
    stems = write_series(scene, tmp_path / "a", workers=2)
    assert stems == ["paper-bench_0000", "paper-bench_0001"]
    frame = read_fixture(tmp_path / "a" / "paper-bench_0001.json")
    assert frame.meta.ground_truth.position_m == [-0.1, 0.1, 0.0]
    assert frame.meta.model_extra["simulator"]["sample"] == 1 and frame.pixels.max() == 255
    again = Scene.model_validate_json((tmp_path / "a" / "scene.json").read_text())
    write_series(again, tmp_path / "b", workers=1)  # one process, same bytes
    for stem in stems:
        assert (tmp_path / "a" / f"{stem}.y").read_bytes() == (tmp_path / "b" / f"{stem}.y").read_bytes()
    assert json.loads((tmp_path / "a" / "map.json").read_text())["beacons"][0]["side_m"] == 0.174


def test_cli_simulate_one_pose_and_locate_it(tmp_path, capsys):
    out = tmp_path / "one"
    assert main(["simulate", "paper-bench", str(out), "--pose", "0.1", "0.2", "0", "--scale", "0.25",
                 "--workers", "1"]) == 0
    assert main(["locate", str(out / "paper-bench_0000.json"), "--map", str(out / "map.json"), "--json"]) == 0
    result = json.loads(capsys.readouterr().out.split("\n", 1)[1])
    assert result["position_m"][:2] == pytest.approx([0.1, 0.2], abs=0.01)


def test_cli_simulate_limit_writes_a_scene_that_lists_its_samples(tmp_path):
    assert main(["simulate", "office", str(tmp_path), "--limit", "2", "--scale", "0.1", "--workers", "1"]) == 0
    scene = Scene.model_validate_json((tmp_path / "scene.json").read_text())
    assert scene.series.path.kind == "poses" and len(scene.series.path.poses) == 2
    assert sorted(p.name for p in tmp_path.glob("*.y")) == ["office_0000.y", "office_0001.y"]


def test_cli_simulate_bad_scene_is_exit_2(tmp_path, capsys):
    (tmp_path / "bad.json").write_text('{"name": "x", "room": {"size_m": [1, 1, -1]}, "beacons": []}')
    assert main(["simulate", str(tmp_path / "bad.json"), str(tmp_path / "out")]) == 2
    assert "size_m" in capsys.readouterr().err


def test_a_walk_carries_its_velocity_into_the_rolling_shutter(tmp_path):
    series = {"path": {"kind": "zigzag", "area_m": [-0.3, -0.3, 0.3, 0.3], "spacing_m": 0.3, "speed_mps": 1.0,
                       "frame_interval_s": 0.1, "height_m": 0.0}}
    scene = small_bench(**series)
    poses = series_poses(scene)
    assert poses[2].velocity_mps == pytest.approx((1.0, 0.0, 0.0))  # along the first leg, east
    assert poses[2].angular_velocity_dps == (0.0, 0.0, 0.0)
    moving, meta = render_pose(scene, poses[2])
    still = render_pose(scene, poses[2].__class__(**{**poses[2].__dict__, "velocity_mps": (0.0, 0.0, 0.0)}))[0]
    assert meta.model_extra["simulator"]["velocity_mps"] == pytest.approx([1.0, 0.0, 0.0])
    assert not np.array_equal(moving, still)
