"""Rendered ID frames of one panel (quarter resolution of the Mi 8 front camera, fixed seeds)."""

import numpy as np
import pytest

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.vlc.capture import stepped_interval_s
from server.vlc.codec import LedWaveform
from shared_schemas import Beacon, FrameKind, device_profiles
from simulator.fixtures import fixture_meta
from simulator.led import row_gains
from simulator.render import CameraPose, SensorModel, render_frame

WIDTH, HEIGHT = 970, 1296
CAMERA = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], WIDTH, HEIGHT)
SKEW_S = 0.03


def id_frames(beacon_id: int, distance_m: float, exposure_s: float, count: int, seed: int,
              ypr=(20.0, 4.0, -3.0), offset_m=(0.05, -0.08), shape: dict | None = None,
              depth: float | None = None) -> list[LumaFrame]:
    """`count` ID frames of one panel, `stepped_interval_s(1/30)` apart, LED at a random phase;
    `shape`: the panel's shape fields (default: the paper's 0.174 m rounded square); `depth`: the
    LED's modulation depth (default the codec's, 0.7; 1.0: off between chips)."""
    rng = np.random.default_rng(seed)
    shape = shape or {"side_m": 0.174, "corner_radius_m": 0.02}
    beacon = Beacon(id=beacon_id, center_m=[0.0, 0.0, distance_m], **shape)
    wave = LedWaveform.for_beacon(beacon_id, depth=depth, phase_s=rng.uniform(0, 1),
                                  clock_error_ppm=rng.uniform(-50, 50))
    pose = CameraPose(np.array([*offset_m, 0.0]), rotation_from_ypr(*ypr))
    sensor = SensorModel(background_dn=3.0, plateau_dn=200.0, psf_sigma_px=1.2, electrons_per_dn=4.0,
                         read_noise_dn=2.0)
    frames = []
    for k in range(count):
        t_s = 5.0 + k * stepped_interval_s(1 / 30)
        gains = row_gains(wave, HEIGHT, SKEW_S / (HEIGHT - 1), exposure_s, t_s)
        pixels = render_frame(beacon, CAMERA, pose, WIDTH, HEIGHT, sensor, rng, row_gain=gains)
        gravity = (pose.rotation_wc.T @ [0, 0, -1.0]).tolist()  # the phone sends it: the pose needs it
        meta = fixture_meta(CAMERA, WIDTH, HEIGHT, pose, gravity_camera=gravity).model_copy(update={
            "exposure_s": exposure_s, "rolling_shutter_skew_s": SKEW_S, "timestamp_ns": int(t_s * 1e9),
            "frame_kind": FrameKind.id})
        frames.append(LumaFrame(pixels, meta, CAMERA))
    return frames


@pytest.fixture
def make_id_frames():
    return id_frames
