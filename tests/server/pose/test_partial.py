"""Pose from the visible part of a cut-off panel (rendered, fixed seed)."""

import numpy as np

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.outcomes import Refusal
from server.pose.partial import edge_points, fit_partial, measure_growth, tilt_from_gravity
from server.vision.beacons import find_beacon_blobs
from shared_schemas import Beacon, device_profiles
from simulator.render import CameraPose, SensorModel, render_frame

WIDTH, HEIGHT = 1940, 2592  # half the Mi 8 front camera
CAMERA = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], WIDTH, HEIGHT)
BEACON = Beacon(id=7, center_m=[0.0, 0.0, 1.4], side_m=0.174, corner_radius_m=0.02)
SENSOR = SensorModel(plateau_dn=255 * 4, psf_sigma_px=1.2)


def render(position, ypr, seed):
    pose = CameraPose(np.array(position, float), rotation_from_ypr(*ypr))
    pixels = render_frame(BEACON, CAMERA, pose, WIDTH, HEIGHT, SENSOR, np.random.default_rng(seed))
    return pose, pixels


def test_tilt_from_gravity_inverts_the_rotation():
    for ypr in ((30.0, 4.0, -7.0), (-100.0, -2.0, 3.0)):
        gravity = rotation_from_ypr(*ypr).T @ [0, 0, -1.0]
        np.testing.assert_allclose(tilt_from_gravity(gravity), ypr[1:], atol=1e-9)


def test_a_cut_off_panel_gives_the_position_to_a_few_millimetres():
    # growth measured on a complete panel of the same exposure and PSF, as the session does
    pose, pixels = render([0.05, 0.02, 0.0], (5.0, 1.0, -2.0), seed=1)
    found = find_beacon_blobs(pixels)
    blob = found.blobs[0]
    assert not blob.cut_off
    growth = measure_growth(BEACON, edge_points(pixels, blob.bounding_box, found.levels.threshold), pose.position_m,
                            pose.rotation_wc, CAMERA)
    assert 0.5 < growth < 4.0  # a clipped panel's mid-level contour lies outside its outline
    # now the panel 0.9 m off the axis: cut by the frame's top border
    pose, pixels = render([0.05, 0.95, 0.0], (8.0, 0.5, 1.0), seed=2)
    found = find_beacon_blobs(pixels)
    assert len(found.blobs) == 1 and found.blobs[0].cut_off
    points = edge_points(pixels, found.blobs[0].bounding_box, found.levels.threshold)
    gravity = pose.rotation_wc.T @ [0, 0, -1.0]
    guess = pose.position_m + [0.08, -0.06, 0.05]
    fit = fit_partial([(BEACON, points)], CAMERA, gravity, guess, 0.0, growth)
    assert not isinstance(fit, Refusal), fit
    assert np.hypot(*(fit.position_m[:2] - pose.position_m[:2])) < 0.005
    assert abs(fit.position_m[2] - pose.position_m[2]) < 0.01
    # without gravity there is no tilt, and the fit says so
    assert "gravity" in fit_partial([(BEACON, points)], CAMERA, None, guess, 0.0, growth).message
