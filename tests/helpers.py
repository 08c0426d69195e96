"""Frames and maps shared by several test modules (not tests themselves)."""

import functools
from pathlib import Path

import numpy as np

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.vlc.codec import LedWaveform
from shared_schemas import Beacon, BeaconMap, FrameKind, FrameMeta, ProfileRef, device_profiles, load_map
from shared_schemas.models import MeasuredPinhole
from simulator.fixtures import fixture_meta
from simulator.led import row_gains
from simulator.render import CameraPose, Emitter, SensorModel, beacon_outline_px, render_emitters, render_frame
from simulator.scene import find_scene
from simulator.survey import render_survey, sketch_of, survey_poses

DARK_WIDTH, DARK_HEIGHT = 48, 64
DARK_CAMERA = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], DARK_WIDTH, DARK_HEIGHT)
ROOM = BeaconMap(
    name="room", beacons=[Beacon(id=1, center_m=[0, 0, 2], side_m=0.2), Beacon(id=2, center_m=[1.2, 0, 2], side_m=0.2)]
)
OTHER_ROOM = ROOM.model_copy(update={"name": "other"})


def dark_frame(kind: FrameKind = FrameKind.pose, t_s: float = 0.0) -> LumaFrame:
    """A tiny frame with nothing in it: the session runs, finds no panel, and answers at once."""
    meta = FrameMeta(
        width=DARK_WIDTH,
        height=DARK_HEIGHT,
        format="Y8",
        camera=DARK_CAMERA,
        timestamp_ns=int(t_s * 1e9),
        frame_kind=kind,
        exposure_s=1 / 8000 if kind is FrameKind.id else 0.01,
        rolling_shutter_skew_s=0.03,
    )
    pixels = np.full((DARK_HEIGHT, DARK_WIDTH), 10, np.uint8)
    pixels.flags.writeable = False
    return LumaFrame(pixels, meta, DARK_CAMERA)


WIDTH, HEIGHT = 970, 1296
CAMERA = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], WIDTH, HEIGHT)
TWO_PANELS = BeaconMap(
    name="two",
    beacons=[
        Beacon(id=17, center_m=[-0.12, -0.2, 1.0], side_m=0.174, corner_radius_m=0.02),
        Beacon(id=42, center_m=[0.12, 0.2, 1.0], side_m=0.174, corner_radius_m=0.02),
    ],
)
POSE = CameraPose(np.array([0.02, -0.03, 0.0]), rotation_from_ypr(10.0, 2.0, -1.0))


def two_panel_frame(level_dn=1000.0, exposure_s=0.01, seed=0, t_s=0.0) -> LumaFrame:
    rng = np.random.default_rng(seed)
    emitters = []
    for beacon in TWO_PANELS.beacons:
        gain = None
        if exposure_s < 1e-3:
            wave = LedWaveform.for_beacon(beacon.id, phase_s=0.001 * beacon.id)
            gain = row_gains(wave, HEIGHT, 0.03 / (HEIGHT - 1), exposure_s, t_s)
        emitters.append(Emitter(beacon_outline_px(beacon, CAMERA, POSE), level_dn, gain))
    pixels = render_emitters(emitters, WIDTH, HEIGHT, SensorModel(psf_sigma_px=1.0), rng)
    gravity = (POSE.rotation_wc.T @ [0, 0, -1.0]).tolist()
    meta = fixture_meta(CAMERA, WIDTH, HEIGHT, POSE, gravity_camera=gravity).model_copy(
        update={
            "exposure_s": exposure_s,
            "rolling_shutter_skew_s": 0.03,
            "timestamp_ns": int(t_s * 1e9),
            "frame_kind": FrameKind.id if exposure_s < 1e-3 else FrameKind.pose,
        }
    )
    return LumaFrame(pixels, meta, CAMERA)


# A calibrated lens unlike its datasheet: fx 3 % longer, fy 1.5 % shorter, the principal point
# 120 px right and 100 px up of the centre at the native 3880 x 5184 (15 and 12.5 px at 1/8).
FRONT = device_profiles()["xiaomi-mi8-front"]
_DATASHEET_FOCAL_PX = FRONT.focal_length_m / FRONT.pixel_size_m
CALIBRATED = FRONT.model_copy(update={
    "id": "mi8-front-calibrated",
    "intrinsics": MeasuredPinhole(fx=_DATASHEET_FOCAL_PX * 1.03, fy=_DATASHEET_FOCAL_PX * 0.985, rms_px=0.2,
                                  cx=(FRONT.width - 1) / 2 + 120, cy=(FRONT.height - 1) / 2 - 100, views=20),
})
DATASHEET = CALIBRATED.model_copy(update={"intrinsics": None})  # the same id, the maker's pinhole
LENS_WIDTH, LENS_HEIGHT = 485, 648  # 1/8 of the native size: 85 px of panel at 1 m


def calibrated_lens_frame(position_m: tuple[float, float, float], seed: int = 0) -> tuple[FrameMeta, bytes]:
    """A Y8 frame of the demo map's panel through the CALIBRATED lens; its camera names CALIBRATED's id."""
    camera = intrinsics_from_profile(CALIBRATED, LENS_WIDTH, LENS_HEIGHT)
    pose = CameraPose(np.array(position_m), rotation_from_ypr(10.0, 2.0, -1.0))
    pixels = render_frame(load_map().beacons[0], camera, pose, LENS_WIDTH, LENS_HEIGHT,
                          SensorModel(psf_sigma_px=1.0), np.random.default_rng(seed))
    gravity = (pose.rotation_wc.T @ [0, 0, -1.0]).tolist()
    meta = fixture_meta(camera, LENS_WIDTH, LENS_HEIGHT, pose, gravity_camera=gravity)
    return meta.model_copy(update={"camera": ProfileRef(profile=CALIBRATED.id)}), pixels.tobytes()


SURVEY_SCALE = 0.25  # of the Mi 8 front camera: 970 x 1296
SURVEY_FRAMES = 12


@functools.cache
def survey_set(frames: int = SURVEY_FRAMES, seed: int = 3):
    """(true map, sketch, anchor ID, shots) of the office (four panels) surveyed by `frames` quarter-scale
    frames (`simulator.survey`), rendered once per test session."""
    scene = find_scene("office")
    scene = scene.model_copy(update={"camera": scene.camera.model_copy(update={"scale": SURVEY_SCALE})})
    rng = np.random.default_rng(seed)
    shots = render_survey(scene, survey_poses(scene, frames, rng), rng)
    truth = scene.beacon_map()
    anchor = truth.beacons[0].id
    return truth, sketch_of(truth, anchor, rng), anchor, tuple(shots)


def survey_frame(shot, name: str, labels=None):
    """A `SurveyFrame` of a rendered survey shot, with its own labels unless others are given."""
    from server.survey.run import SurveyFrame

    meta = FrameMeta.model_validate(shot.meta.model_dump(by_alias=True))
    return SurveyFrame(
        name, LumaFrame(shot.pixels, meta, shot.meta.camera), list(shot.labels if labels is None else labels)
    )


def walk_frames(captures):
    """A walk's frames as the app sends them: each capture's ID frames, then its pose frame."""
    for capture in captures:
        yield from capture.id_frames
        yield capture.pose_frame


def answer_without_timings(result) -> dict:
    """A result as JSON without its timings: what two ways of locating one frame must agree on."""
    return result.model_dump(mode="json", exclude={"timing_ms"})


# A 0.6 m panel of 10 mm corner radius (issue 27), a map that gets its corner radius wrong, and a room of
# two panels of different shapes: frames of the first are `render_panel_frame`'s
PANEL = BeaconMap(name="panel", beacons=[Beacon(id=1, center_m=[0, 0, 1], side_m=0.6, corner_radius_m=0.01)])
PANEL_WRONG_RADIUS = BeaconMap(name="panel-r05", beacons=[PANEL.beacons[0].model_copy(update={"corner_radius_m": 0.05})])
TWO_SHAPES = BeaconMap(
    name="two-shapes",
    beacons=[PANEL.beacons[0], Beacon(id=2, center_m=[2.0, 0, 1], side_m=0.3, corner_radius_m=0.03)],
)


def render_panel_frame(folder) -> str:
    """`lumipose render` of PANEL from (0.1, 0.2, 0), ypr (5, 2, -1), at quarter scale: the frame's JSON path."""
    from lumipose_cli.main import main

    panel = folder / "panel.json"
    panel.write_text(PANEL.model_dump_json())
    stem = str(folder / "mine")
    args = ["--map", str(panel), "--position", "0.1", "0.2", "0", "--ypr", "5", "2", "-1", "--scale", "0.25"]
    assert main(["render", stem, *args]) == 0
    return f"{stem}.json"


def process_status_kib(pid: int, field: str) -> float:
    """A memory figure of a running process (`VmRSS`, `VmHWM`, ...) from /proc/<pid>/status, in KiB."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return float(line.split()[1])
    raise KeyError(field)
