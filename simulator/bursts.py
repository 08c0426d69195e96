"""A scene rendered as the app captures it: a pose frame, then a burst of ID frames right after it.

docs/vlc.md, "Capture protocol": the pose frame with the scene's own sensor and camera, then
`ID_BURST_FRAMES` frames (`frame_kind` "id") with the scene's `id_frames` settings (1/8000 s,
ISO raised), each `id_frame_interval_s` (a quarter message) after the one before. Every frame
carries its own first-row exposure start (`timestamp_ns`), exposure, ISO and rolling-shutter
skew; the camera may move between the frames. `lumipose simulate --bursts` and `bench office`
both render their captures here.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from server.vlc.capture import ID_BRIGHTNESS_FRACTION, ID_BURST_FRAMES, id_frame_interval_s
from shared_schemas import FrameKind, FrameMeta
from simulator.render import CameraPose, ReadoutMotion
from simulator.scene import Scene, render_sample

ID_GAP_S = 0.02  # from the pose frame's exposure end to the first ID frame's start: the app's next frame slot
MIN_ISO, MAX_ISO = 25.0, 12800.0  # SensorSpec's range


def burst_scenes(scene: Scene) -> tuple[Scene, Scene]:
    """(pose-frame scene, ID-frame scene): the scene itself, and the scene with its `id_frames` settings."""
    spec = scene.id_frames
    pose_sensor = scene.sensor
    # the phone raises the ISO so the short frame keeps a fixed share of the pose frame's brightness
    raised_iso = pose_sensor.iso * pose_sensor.exposure_s / spec.exposure_s * ID_BRIGHTNESS_FRACTION
    iso = spec.iso if spec.iso is not None else float(np.clip(raised_iso, MIN_ISO, MAX_ISO))
    id_sensor = pose_sensor.model_copy(update={"exposure_s": spec.exposure_s, "iso": iso})
    id_camera = scene.camera if spec.scale is None else scene.camera.model_copy(update={"scale": spec.scale})
    return scene, scene.model_copy(update={"sensor": id_sensor, "camera": id_camera})


def id_frame_times(
    t_s: float, pose_exposure_s: float, frames: int = ID_BURST_FRAMES, interval_s: float = id_frame_interval_s()
) -> list[float]:
    """First-row exposure starts of the ID frames after a pose frame that starts at `t_s`."""
    return [t_s + pose_exposure_s + ID_GAP_S + j * interval_s for j in range(frames)]


def burst_span_s(scene: Scene) -> float:
    """From the start of a capture's pose frame to the end of its last ID frame's exposure."""
    return id_frame_times(0.0, scene.sensor.exposure_s)[-1] + scene.id_frames.exposure_s


def capture_starts(times_s: list[float], span_s: float) -> list[float]:
    """Each capture's start: its sample's time, later where the capture before it is still running
    (an untimed series, a walk faster than a burst), so that the frames' timestamps only grow."""
    starts: list[float] = []
    for t_s in times_s:
        starts.append(t_s if not starts else max(t_s, starts[-1] + span_s + ID_GAP_S))
    return starts


def render_burst(
    scenes: tuple[Scene, Scene],
    t_s: float,
    pose_at: Callable[[float], CameraPose],
    rng: np.random.Generator,
    frames: int = ID_BURST_FRAMES,
    interval_s: float = id_frame_interval_s(),
    motion_of: Callable[[Scene], ReadoutMotion | None] = lambda scene: None,
    **extra,
) -> list[tuple[np.ndarray, FrameMeta]]:
    """One capture in capture order: (pixels, FrameMeta) of the pose frame at `t_s`, then of its ID frames.

    `pose_at(t)` is the camera's pose at time t; `motion_of(scene)` its rolling-shutter motion
    for a frame of that scene; `extra` goes into every frame's metadata (with `burst_frame`, the
    frame's place in the capture, added to a `simulator` block when there is one).
    """
    pose_scene, id_scene = scenes
    shots = [(pose_scene, t_s, FrameKind.pose)]
    shots += [
        (id_scene, t, FrameKind.id) for t in id_frame_times(t_s, pose_scene.sensor.exposure_s, frames, interval_s)
    ]
    rendered = []
    for k, (scene, t, kind) in enumerate(shots):
        fields = dict(extra)
        if "simulator" in fields:
            fields["simulator"] = {**fields["simulator"], "burst_frame": k}
        rendered.append(render_sample(scene, pose_at(t), rng, t, motion_of(scene), frame_kind=kind.value, **fields))
    return rendered
