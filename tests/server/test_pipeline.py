"""Round trips: render a known pose, locate it, compare at a stated tolerance (fixed seeds)."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame, read_fixture
from server.locator import locate as locate_frame
from server.options import LocateOptions
from server.pipeline import CornerMethod, PipelineOptions
from server.pose.consistency import ConsistencyRules
from server.pose.solve import GravityMode
from shared_schemas import Beacon, BeaconMap, FailureReason, device_profiles, load_map
from simulator.fixtures import fixture_meta
from simulator.render import CameraPose, SensorModel, render_frame

FIXTURE = Path(__file__).parents[1] / "fixtures" / "bench_1m.json"
PROFILE = device_profiles()["xiaomi-mi8-front"]
WIDTH, HEIGHT = 970, 1296  # a quarter of the Mi 8 front camera's resolution
CAMERA = intrinsics_from_profile(PROFILE, WIDTH, HEIGHT)
BEACON = Beacon(id=0, center_m=[0, 0, 1.0], side_m=0.174, corner_radius_m=0.02)
MAP = BeaconMap(name="bench", beacons=[BEACON])


def locate(frame, beacon_map, options=PipelineOptions()):
    return locate_frame(frame, beacon_map, LocateOptions(pipeline=options))


def frame_at(position, ypr, seed=0, sensor=SensorModel(), camera=CAMERA, gravity=True) -> LumaFrame:
    pose = CameraPose(np.array(position, float), rotation_from_ypr(*ypr))
    pixels = render_frame(BEACON, camera, pose, WIDTH, HEIGHT, sensor, np.random.default_rng(seed))
    g = (pose.rotation_wc.T @ [0, 0, -1.0]).tolist() if gravity else None
    return LumaFrame(pixels, fixture_meta(camera, WIDTH, HEIGHT, pose, gravity_camera=g), camera)


def error_2d_mm(result, position) -> float:
    assert result.ok, result.message
    return 1000 * float(np.hypot(*(np.array(result.position_m[:2]) - position[:2])))


@pytest.mark.parametrize("seed", range(4))
def test_quarter_resolution_frames_are_located_to_a_few_millimetres(seed):
    rng = np.random.default_rng(seed)
    position = np.array([*rng.uniform(-0.3, 0.3, 2), 0.0])
    ypr = (rng.uniform(-30, 30), *rng.uniform(-4, 4, 2))
    result = locate(frame_at(position, ypr, seed), MAP, PipelineOptions(gravity_mode=GravityMode.never))
    # a quarter-resolution panel is ~170 px wide: 3 mm is ~0.1 % of its 1 m range
    assert error_2d_mm(result, position) < 3.0
    assert result.reprojection_error_px < 0.2
    assert set(result.timing_ms) >= {"roi", "blur", "threshold", "contour", "polygon", "subpixel", "pose", "total"}


def test_clipped_edge_correction_is_what_removes_the_range_bias():
    position = np.array([0.25, 0.3, 0.0])
    frame = frame_at(position, (0, 0, 0), sensor=SensorModel(plateau_dn=255 * 6, psf_sigma_px=1.5))
    corrected = locate(frame, MAP, PipelineOptions(gravity_mode=GravityMode.never))
    uncorrected = locate(frame, MAP, PipelineOptions(gravity_mode=GravityMode.never, subpixel=False))
    # the uncorrected panel looks too big, hence too close
    assert uncorrected.position_m[2] > corrected.position_m[2]
    # measured at a quarter resolution: 22 mm range bias uncorrected, 0.04 mm corrected (the corner
    # geometry; the blurred-step fit it replaced left 10 mm). 3 mm is 0.5 px of the panel's 170 px.
    assert abs(uncorrected.position_m[2]) > 0.015
    assert abs(corrected.position_m[2]) < 0.003
    assert error_2d_mm(corrected, position) < error_2d_mm(uncorrected, position)


def test_lens_distortion_is_undone():
    distorted = CAMERA.model_copy(update={"distortion": [0.08, -0.05, 0.0, 0.0, 0.0]})
    position = np.array([0.3, -0.35, 0.0])
    frame = frame_at(position, (5, 2, -2), camera=distorted)
    with_model = locate(frame, MAP, PipelineOptions(gravity_mode=GravityMode.never))
    undistorted = LumaFrame(frame.pixels, frame.meta, CAMERA)
    unchecked = PipelineOptions(gravity_mode=GravityMode.never, consistency=ConsistencyRules(check=False))
    ignoring = locate(undistorted, MAP, unchecked)
    assert error_2d_mm(with_model, position) < 3.0
    assert error_2d_mm(ignoring, position) > 2 * error_2d_mm(with_model, position)
    # the bent corners are no view of the square: beyond their noise (the chi-square alone refuses them),
    # though within the 2 px the test leaves to what its noise model does not hold yet (a moving camera)
    statistics_only = ConsistencyRules(min_rms_px=0.0)
    refused = locate(undistorted, MAP, PipelineOptions(gravity_mode=GravityMode.never, consistency=statistics_only))
    assert not refused.ok and refused.reason is FailureReason.shape_mismatch


def test_square_corner_path_refuses_the_rounded_panel():
    result = locate(frame_at([0.1, 0.1, 0], (0, 0, 0)), MAP, PipelineOptions(corner_method=CornerMethod.square))
    assert not result.ok and result.reason is FailureReason.not_four_sides


def test_frames_without_a_usable_beacon_are_refused():
    dark = LumaFrame(np.full((HEIGHT, WIDTH), 9, np.uint8), frame_at([0, 0, 0], (0, 0, 0)).meta, CAMERA)
    assert locate(dark, MAP).reason is FailureReason.no_beacon
    sliver = frame_at([0.58, 0.0, 0.0], (8, 0, 0))  # a few pixels of one side at the left border
    refused = locate(sliver, MAP)
    assert refused.reason is FailureReason.beacon_cut_off, refused
    two = BeaconMap(name="two", beacons=[BEACON, BEACON.model_copy(update={"id": 1, "center_m": [2, 0, 1]})])
    assert locate(frame_at([0, 0, 0], (0, 0, 0)), two).reason is FailureReason.unknown_beacon


@pytest.mark.parametrize(
    "position, ypr", [([0.5, 0.03, 0.0], (7, 2, -1)), ([0.0, 0.62, 0.0], (5, 1, 1))], ids=["left-border", "top-border"]
)
def test_a_panel_half_cut_by_the_border_is_fixed_from_its_visible_outline(position, ypr):
    result = locate(frame_at(position, ypr, seed=2), MAP)
    assert result.ok, result.message
    assert "cut by the frame border" in result.warnings[0]
    sigma = np.asarray(result.position_sigma_m)
    assert np.all(sigma > 0) and np.all(sigma < 0.005)
    assert error_2d_mm(result, position) < 3.0
    assert result.corners_px is not None and result.orientation_rule is not None


def test_a_cut_panel_whose_visible_part_fits_two_poses_is_refused_not_guessed():
    result = locate(frame_at([0.5, 0.03, 0.0], (25, 4, -3), seed=2), MAP)
    # two minima 56 mm apart: either two answers, or one so uncertain that it is no fix
    assert result.reason in (FailureReason.pose_ambiguous, FailureReason.pose_uncertain), result
    assert "two poses" in result.message or "fixes the position only to" in result.message


def test_cli_locates_the_bundled_fixture_as_the_readme_says():
    truth = read_fixture(FIXTURE).meta.ground_truth.position_m
    run = subprocess.run([sys.executable, "-m", "lumipose_cli", "locate", str(FIXTURE), "--json"],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    import json

    result = json.loads(run.stdout)
    assert np.hypot(*(np.subtract(result["position_m"][:2], truth[:2]))) < 0.003
    assert result["beacon_id"] == 0 and result["orientation_rule"] == "yaw_within_45deg"


def test_cli_exit_codes_for_bad_input(tmp_path):
    (tmp_path / "bad.json").write_text('{"width": 4, "height": 4, "camera": {"fx": "NaN"}}')
    (tmp_path / "bad.y").write_bytes(bytes(16))
    run = subprocess.run([sys.executable, "-m", "lumipose_cli", "locate", str(tmp_path / "bad.json")],
                         capture_output=True, text=True, check=False)
    assert run.returncode == 2 and "error:" in run.stderr


def bench_outcome(scene, label):
    """Render and locate one sample of a benchmark scene, as the benchmark does."""
    from simulator.reports import LocateJob, locate_sample
    from simulator.sampling import series_poses

    sample = next(s for s in series_poses(scene) if s.label == label)
    return locate_sample(LocateJob(scene, sample))


@pytest.mark.parametrize("label", ["2,1", "-3,0"])
def test_face_to_face_frames_with_sides_along_the_pixel_grid(label):
    """`lumipose bench grid` (full resolution, yaw 0: every side along a pixel row or column).
    Two of its worst points: 7.2 and 5.0 mm when the pixel-locking term was fitted on such
    sides (ba27a16), 1.20 and 1.06 mm measured since; 3 mm is the grid's target maximum."""
    from simulator.bench_grid import grid_scene

    outcome = bench_outcome(grid_scene(), label)
    assert outcome.reason is None, outcome.message
    assert outcome.error_2d_m < 0.003


@pytest.mark.parametrize("distance_m, label", [(1.7, "1,0"), (2.1, "0,-2")])
def test_distance_bench_frames_that_crashed_are_located(distance_m, label):
    """`lumipose bench distance --distances 1.7 2.1`: at 64752c6 these face-to-face frames made
    IPPE_SQUARE return NaN minima and locate raised on a NaN ambiguity ratio (the corners
    themselves are replayed in tests/server/pose/test_solve.py, as later pipeline changes moved them
    off the exact degenerate case). Measured since: 1.5 and 2.1 mm."""
    from simulator.bench_grid import grid_scene
    from simulator.bench_sweeps import distance_scene

    outcome = bench_outcome(distance_scene(grid_scene(), distance_m), label)
    assert outcome.reason is None, outcome.message  # "pipeline_error" is a crash
    assert outcome.error_2d_m < 0.005
