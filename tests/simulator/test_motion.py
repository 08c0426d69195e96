"""Motion during the exposure and the readout (issue 13 item 1): skew, blur, the knob's draws."""

from dataclasses import replace

import numpy as np
import pytest

from server.geometry import rotation_from_ypr
from shared_schemas import CameraIntrinsics
from simulator.bench_fidelity import edge_points
from simulator.benchmarks import AccuracyConfig, accuracy_frame, bench_motion, position_seen_m
from simulator.chain import ChainSpec
from simulator.motion import MotionSpec, draw_velocities
from simulator.render import (
    CameraPose, Emitter, ReadoutMotion, SensorModel, exposure_polygons_px, render_signal, world_polygon_px,
)
from simulator.scene import SensorSpec, hand_motion

CAMERA = CameraIntrinsics(fx=977.78, fy=977.78, cx=239.5, cy=319.5)
WIDTH, HEIGHT = 480, 640
ROW_TIME_S = 0.03 / (HEIGHT - 1)
HALF_SIDE_M = 0.087
SQUARE_M = np.array([[-HALF_SIDE_M, -HALF_SIDE_M, 1.0], [HALF_SIDE_M, -HALF_SIDE_M, 1.0],
                     [HALF_SIDE_M, HALF_SIDE_M, 1.0], [-HALF_SIDE_M, HALF_SIDE_M, 1.0]])
STILL = CameraPose(np.zeros(3), np.eye(3))
SENSOR = SensorModel(background_dn=10.0, plateau_dn=0.0, psf_sigma_px=1.0)
LEVEL_DN = 200.0  # below saturation: the light itself, no clipping


def _light(motion: ReadoutMotion | None, pose: CameraPose = STILL) -> np.ndarray:
    """The noiseless light of the square (1 m ahead) seen from `pose` moving by `motion`."""
    outline, during = exposure_polygons_px(SQUARE_M, CAMERA, pose, WIDTH, HEIGHT, 0.5, motion)
    return render_signal([Emitter(outline, LEVEL_DN, exposure_outlines_px=during)], WIDTH, HEIGHT, SENSOR)


def _left_edge(light: np.ndarray, rows=(250, 390)) -> np.ndarray:
    return edge_points(light, 10.0 + LEVEL_DN / 2, "left", rows)


def _edge_spread_px2(light: np.ndarray, row: int) -> float:
    """Second central moment (px^2) of the left edge's gradient along `row`: the blur across the edge."""
    profile = light[row, : WIDTH // 2]
    gradient = np.clip(np.diff(profile), 0.0, None)
    x = np.arange(len(gradient)) + 0.5
    mean = np.sum(x * gradient) / np.sum(gradient)
    return float(np.sum((x - mean) ** 2 * gradient) / np.sum(gradient))


def test_a_turn_during_the_readout_skews_the_outline_by_rate_x_row_time_x_fx():
    """Turning about the map's y axis (the image's vertical) moves each row's outline sideways by
    fx (1 + (x / z)^2) omega (r t_row + t_exp / 2): a straight, slanted left side."""
    rate_dps, exposure_s = 20.0, 1e-4  # a short exposure: the skew alone (blur 0.03 px, not drawn)
    motion = ReadoutMotion(np.zeros(3), np.array([0.0, rate_dps, 0.0]), ROW_TIME_S, exposure_s)
    assert exposure_polygons_px(SQUARE_M, CAMERA, STILL, WIDTH, HEIGHT, 0.5, motion)[1] == ()
    left = _left_edge(_light(motion))
    slope, offset = np.polyfit(left[:, 1], left[:, 0], 1)
    omega = np.radians(rate_dps)
    gain = CAMERA.fx * (1 + HALF_SIDE_M**2)  # d(fx x / z) / d(turn) at x / z = -0.087
    assert slope == pytest.approx(-gain * omega * ROW_TIME_S, rel=0.02)
    still_x = _left_edge(_light(None))[:, 0].mean()
    expected_at_320 = still_x - gain * omega * (320 * ROW_TIME_S + exposure_s / 2)
    assert slope * 320 + offset == pytest.approx(expected_at_320, abs=0.05)


@pytest.mark.parametrize("speed_mps", [0.3, 0.6])
def test_the_edge_blur_along_the_motion_grows_as_the_travel_during_the_exposure(speed_mps):
    """Moving along x, each row integrates the edge over a travel L = fx v t_exp / Z: the edge's
    spread (variance of its gradient) grows by L^2 / 12, that of a box; its middle stays where the
    row sees it at mid-exposure."""
    exposure_s = 0.01
    motion = ReadoutMotion(np.array([speed_mps, 0.0, 0.0]), np.zeros(3), ROW_TIME_S, exposure_s)
    travel_px = CAMERA.fx * speed_mps * exposure_s / 1.0
    blurred, sharp = _light(motion), _light(None)
    rows = range(300, 340, 8)
    added = np.mean([_edge_spread_px2(blurred, r) - _edge_spread_px2(sharp, r) for r in rows])
    assert added == pytest.approx(travel_px**2 / 12, rel=0.03)
    # the blurred edge's middle is the edge seen at mid-exposure (the skew's own outline, no blur)
    mid_only = render_signal([Emitter(world_polygon_px(SQUARE_M, CAMERA, STILL, WIDTH, HEIGHT, 0.5, motion),
                                      LEVEL_DN)], WIDTH, HEIGHT, SENSOR)
    assert np.mean(_left_edge(blurred)[:, 0] - _left_edge(mid_only)[:, 0]) == pytest.approx(0.0, abs=0.03)
    assert (blurred.sum() - sharp.sum()) / sharp.sum() == pytest.approx(0.0, abs=1e-4)  # blur keeps the light


def test_no_motion_draws_nothing_and_renders_the_still_frame():
    """A still knob draws nothing (the frame's noise stays what it was) and the renderer takes its
    old path: no exposure outlines (byte-identical frames; checked against the commit before, see
    docs/simulator.md)."""
    rng = np.random.default_rng(5)
    state = rng.bit_generator.state
    assert hand_motion(MotionSpec(), rng, SensorSpec(), HEIGHT) is None
    assert rng.bit_generator.state == state
    assert exposure_polygons_px(SQUARE_M, CAMERA, STILL, WIDTH, HEIGHT, 0.5, None)[1] == ()
    plain = render_signal([Emitter(world_polygon_px(SQUARE_M, CAMERA, STILL, WIDTH, HEIGHT, 0.5), LEVEL_DN)],
                          WIDTH, HEIGHT, SENSOR)
    assert np.array_equal(_light(None), plain)
    config = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, chain=ChainSpec(motion=MotionSpec()))
    frame, _, pose = accuracy_frame(config, 0)
    assert bench_motion(config, 0, frame.meta.height) is None
    assert np.array_equal(position_seen_m(pose, None, frame.camera, [0.0, 0.0, 1.0]), pose.position_m)
    assert np.array_equal(frame.pixels, accuracy_frame(AccuracyConfig(distance_m=1.0, frames=1, scale=0.1,
                                                                      chain=ChainSpec()), 0)[0].pixels)
    # slower than BLUR_STEP_PX per exposure: the outline at mid-exposure only, as before blur was drawn
    slow = ReadoutMotion(np.array([0.01, 0.0, 0.0]), np.zeros(3), ROW_TIME_S, 0.01)  # 0.1 px
    assert exposure_polygons_px(SQUARE_M, CAMERA, STILL, WIDTH, HEIGHT, 0.5, slow)[1] == ()


@pytest.mark.parametrize("spec", [MotionSpec.tremor(), MotionSpec.walking()])
def test_the_draws_have_the_documented_rms_in_a_random_direction(spec):
    rng = np.random.default_rng(3)
    draws = [draw_velocities(spec, rng) for _ in range(4000)]
    velocity = np.array([v for v, _ in draws])
    angular = np.array([w for _, w in draws])
    np.testing.assert_allclose(angular.std(axis=0), spec.angular_rate_rms_dps, rtol=0.05)
    np.testing.assert_allclose(np.abs(angular.mean(axis=0)), 0.0, atol=0.1 * spec.angular_rate_rms_dps)
    assert velocity[:, 2].std() == pytest.approx(spec.velocity_rms_mps, rel=0.05)  # no steady vertical part
    horizontal = np.linalg.norm(velocity[:, :2], axis=1)
    if spec.speed_mps:
        assert horizontal.mean() == pytest.approx(spec.speed_mps, rel=0.02)
        np.testing.assert_allclose(velocity[:, :2].mean(axis=0), 0.0, atol=0.05 * spec.speed_mps)  # any heading
    else:
        np.testing.assert_allclose(velocity.std(axis=0), spec.velocity_rms_mps, rtol=0.05)


def test_velocities_are_in_the_map_frame_and_the_reference_is_the_panel_rows_pose():
    """A camera turned 90 degrees about its axis, moving along map +x: the image moves along the
    camera axis that map x is now (-R^T x, not the image's x)."""
    pose = CameraPose(np.zeros(3), rotation_from_ypr(90.0, 0.0, 0.0))
    motion = ReadoutMotion(np.array([0.5, 0.0, 0.0]), np.zeros(3), 0.0, 0.01)
    start, end = (world_polygon_px(SQUARE_M, CAMERA, pose, WIDTH, HEIGHT, 0.5, replace(motion, instant=instant))
                  for instant in (0.0, 1.0))
    shift = (end - start).mean(axis=0)
    expected = -(pose.rotation_wc.T @ [1.0, 0.0, 0.0])[:2]
    assert shift @ expected / np.linalg.norm(shift) == pytest.approx(1.0, abs=1e-4)
    assert np.linalg.norm(shift) == pytest.approx(CAMERA.fx * 0.5 * 0.01, rel=0.01)
    # the bench's reference: where the camera is when the panel centre's row is read, mid-exposure
    rolling = ReadoutMotion(np.array([1.0, 0.0, 0.0]), np.zeros(3), ROW_TIME_S, 0.01)
    seen = position_seen_m(STILL, rolling, CAMERA, [0.0, 0.0, 1.0])
    np.testing.assert_allclose(seen, [CAMERA.cy * ROW_TIME_S + 0.005, 0.0, 0.0])


def test_the_bench_and_the_scene_draw_the_same_way():
    config = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, chain=ChainSpec(motion=MotionSpec.walking()))
    motion = bench_motion(config, 0, 518)
    rng = np.random.default_rng([config.seed, 0, 1000, 14])
    again = hand_motion(MotionSpec.walking(), rng, SensorSpec(), 518)
    np.testing.assert_array_equal(motion.velocity_mps, again.velocity_mps)
    assert motion.row_time_s == pytest.approx(0.03 / 517) and motion.exposure_s == 0.01
    assert np.linalg.norm(motion.velocity_mps[:2]) == pytest.approx(1.2, abs=0.4)


def test_the_scene_path_draws_the_chains_motion_on_the_sensors_own_rows():
    """`render_through_chain` draws `chain.motion` once per frame; a binning sensor (twice the rows
    in the same skew) sees the same motion, so the same panel."""
    from simulator.sampling import render_pose, series_poses
    from simulator.scene import find_scene
    from simulator.chain import PixelSpec

    scene = find_scene("paper-bench")
    scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"scale": 0.1})})
    sample = series_poses(scene)[100]
    frames = [render_pose(scene.model_copy(update={"chain": chain}), sample)[0] > 128 for chain in (
        ChainSpec(), ChainSpec(motion=MotionSpec.walking()),
        ChainSpec(pixels=PixelSpec(binning=2), motion=MotionSpec.walking()))]
    still, walking, binned = (frame.sum() for frame in frames)
    assert not np.array_equal(frames[0], frames[1])
    assert walking > still  # the blur stretches the clipped panel along the walk
    assert binned == pytest.approx(walking, rel=0.03)


def test_the_instants_follow_the_part_in_the_frame_not_points_projected_far_out():
    """A wall beside the camera (cut at the near plane) projects points far off the frame; its blur
    takes as many instants as its part in the frame moves (the office window: 256 -> about 12)."""
    wall_m = np.array([[-0.5, -0.3, 0.001], [-0.5, -0.3, 2.0], [-0.5, 0.3, 2.0], [-0.5, 0.3, 0.001]])
    motion = ReadoutMotion(np.array([0.8, 0.0, 0.0]), np.zeros(3), ROW_TIME_S, 0.0084)
    outline, during = exposure_polygons_px(wall_m, CAMERA, STILL, WIDTH, HEIGHT, 1.0, motion)
    assert np.abs(outline).max() > 10 * WIDTH  # points projected far out ...
    assert 1 < len(during) < 256  # ... do not set the number of instants
