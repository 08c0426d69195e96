"""The outline fit judged as a shape test (`server.pose.shape`): the edge noise measured without a
model, the test's three checks on made-up residuals, a wrong-shape blob cut by the frame border
refused whatever the map's required_sigma_m, and real photos of rooms and lamps (none of a
Lumipose panel, tests/fixtures/real_photos/manifest.json) refused at required_sigma_m 1 m."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from server.camera import intrinsics_from_profile, resolve_profile_args
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame, read_photo_file
from server.locator import locate
from server.pose.shape import ShapeRules, covered_share, shape_refusal, shape_test
from server.vision.outline import run_scatter_px
from shared_schemas import Beacon, BeaconMap, FailureReason, PanelShape, device_profiles
from simulator.fixtures import fixture_meta
from simulator.render import CameraPose, SensorModel, render_frame

PHOTOS = Path(__file__).parents[2] / "fixtures" / "real_photos"
RULES = ShapeRules()
PANEL = Beacon(id=0, center_m=[0, 0, 1.4], side_m=0.6, corner_radius_m=0.01)


def noisy_circle(sigma_px: float, radius_px: float = 60.0, count: int = 400, seed: int = 0) -> np.ndarray:
    """Points (count, 2) in order on a circle, each moved along its radius by N(0, sigma)."""
    rng = np.random.default_rng(seed)
    angle = np.linspace(0, 2 * math.pi, count, endpoint=False)
    radius = radius_px + rng.normal(0, sigma_px, count)
    return np.column_stack([radius * np.cos(angle), radius * np.sin(angle)]) + 200


@pytest.mark.parametrize("sigma_px", [0.05, 0.1, 0.3])
def test_run_scatter_measures_the_points_noise_on_a_curved_edge(sigma_px):
    measured = run_scatter_px(noisy_circle(sigma_px))
    assert measured == pytest.approx(sigma_px, rel=0.2)


def test_run_scatter_skips_the_gap_where_the_frame_cut_the_outline():
    points = noisy_circle(0.1)
    cut = np.vstack([points[:150], points[250:]])  # a 100-point gap: its one triple is left out
    assert run_scatter_px(cut) == pytest.approx(0.1, rel=0.2)
    assert math.isnan(run_scatter_px(points[:10]))


def test_residuals_at_the_edge_noise_pass():
    rng = np.random.default_rng(1)
    points = noisy_circle(0.05)
    residuals = rng.normal(0, math.hypot(0.05, RULES.locking_px), len(points))
    test = shape_test(residuals, 9, 0.05, points, points, 1.0)
    assert test.chi2 < test.limit and test.explained > 0.99 and test.covered == 1.0
    assert shape_refusal(test, PANEL) is None


def test_residuals_far_beyond_the_edge_noise_are_a_shape_mismatch():
    rng = np.random.default_rng(2)
    points = noisy_circle(0.05)
    residuals = 0.2 * np.sin(np.linspace(0, 8 * math.pi, len(points))) + rng.normal(0, 0.02, len(points))
    refusal = shape_refusal(shape_test(residuals, 9, 0.05, points, points), PANEL)
    assert refusal is not None and refusal.reason is FailureReason.shape_mismatch
    assert (
        "px RMS from map beacon 0's rounded square" in refusal.message
        and "expected from the edge noise" in refusal.message
    )


def test_an_outline_explained_only_in_part_is_a_shape_mismatch():
    points = noisy_circle(0.05)
    residuals = np.where(np.arange(len(points)) < 300, 0.0, 2.0)  # a quarter of the points 2 px off
    refusal = shape_refusal(shape_test(residuals, 9, 0.05, points, points), PANEL)
    assert refusal is not None and "75% of the visible outline's points" in refusal.message


def test_a_model_outline_in_view_without_edges_along_it_is_a_shape_mismatch():
    points = noisy_circle(0.05)
    model = np.vstack([points, points + [400, 0]])  # half of the model's outline where no edge is
    refusal = shape_refusal(shape_test(np.zeros(len(points)), 9, 0.05, model, points), PANEL)
    assert refusal is not None and "50% of the outline" in refusal.message


def cut_frame(beacon: Beacon, from_border_px: float, seed: int) -> LumaFrame:
    """A level camera 1.4 m under `beacon`, placed so that its centre is `from_border_px` inside the
    frame's right border (a quarter of the Mi 8 front camera's resolution)."""
    width, height = 970, 1296
    camera = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], width, height)
    x = -(width - from_border_px - camera.cx) / camera.fx * 1.4
    pose = CameraPose(np.array([x, 0.05, 0.0]), rotation_from_ypr(0, 2, -1))
    pixels = render_frame(beacon, camera, pose, width, height, SensorModel(), np.random.default_rng(seed))
    gravity = (pose.rotation_wc.T @ [0, 0, -1.0]).tolist()
    return LumaFrame(pixels, fixture_meta(camera, width, height, pose, gravity_camera=gravity, heading_deg=0.0), camera)


@pytest.mark.parametrize("from_border_px", [30, 60])
def test_a_round_lamp_cut_by_the_border_is_no_fix_with_a_square_map(from_border_px):
    lamp = Beacon(id=0, center_m=[0, 0, 1.4], shape=PanelShape.circle, diameter_m=0.3)
    result = locate(cut_frame(lamp, from_border_px, 0), BeaconMap(name="square", beacons=[PANEL], required_sigma_m=1.0))
    assert not result.ok


@pytest.mark.parametrize("from_border_px", [30, 60])
def test_the_map_s_own_panel_cut_by_the_border_stays_a_fix(from_border_px):
    result = locate(cut_frame(PANEL, from_border_px, 0), BeaconMap(name="square", beacons=[PANEL]))
    assert result.ok, f"{result.reason}: {result.message}"


MANIFEST = json.loads((PHOTOS / "manifest.json").read_text())["photos"]


@pytest.mark.parametrize("entry", MANIFEST, ids=[e["file"] for e in MANIFEST])
def test_real_photos_of_rooms_and_lamps_are_no_fix_at_one_metre(entry):
    profiles, profile = resolve_profile_args(["xiaomi-mi8-rear"])
    frame = read_photo_file(PHOTOS / entry["file"], profiles, None, profile)[0]
    for beacon in (Beacon(id=0, center_m=[0, 0, 1.0], side_m=0.174, corner_radius_m=0.02), PANEL,
                   Beacon(id=0, center_m=[0, 0, 1.4], width_m=1.2, height_m=0.3, corner_radius_m=0.01)):  # fmt: skip
        result = locate(frame, BeaconMap(name="real-photos", beacons=[beacon], required_sigma_m=1.0))
        assert not result.ok, f"{entry['file']} ({entry['shows']}) located with a {beacon.extent_m} m panel"


def test_covered_share_counts_non_finite_points_as_before_the_k_d_tree():
    # the k-d tree (issue 30) refuses NaN; the distance matrix it replaced let a NaN point meet nothing
    model = np.array([[0.0, 0.0], [1.0, 0.0], [np.nan, 0.0], [5.0, 5.0]])
    points = np.array([[0.0, 0.1], [np.inf, 1.0], [1.0, -0.1]])
    assert covered_share(model, points, tolerance_px=0.5) == 0.5
    assert covered_share(model, np.full((2, 2), np.nan), tolerance_px=0.5) == 0.0
