"""Survey frames of a room of panels: a hand-held phone photographing the ceiling from the floor.

Each frame (`survey_poses`): the phone at 1.2-1.6 m anywhere under the ceiling, aimed at a point
between two neighbouring panels (jittered), tilted up to `max_tilt_deg` from the vertical, and
turned about its optical axis at random (so the cameras' yaws cover the circle); kept when two or
more panels have their centres in view. Panels partly in view stay in the frame, cut by its
border. Every frame (`render_survey`) is a pose frame of the scene's sensor (its gravity reading
with the scene's sensor error), with a compass reading: the true bearing of the image's +x laid
level (`true_bearing_deg` of the map's +X minus the camera's yaw) plus an indoor compass error,
and labels from the true projection: for every panel with `min_label_px` or more of its image in
view, the centroid of its visible part (inside it: the visible part of a convex panel is convex).

The compass error is a bias shared by every frame of one survey plus each frame's own noise: a
building's steel and wiring deflect the field alike over a room (the slowly varying "systematic
deviations" of Ettlinger, Wieser and Neuner, NAVIGATION 71(1), 2024, navi.632, whose best indoor
heading still errs by 17.4 degrees RMS), while the hand's motion and local anomalies scatter each
reading. 10 degrees of each: 14 degrees per frame, as the 15 degrees (all independent) before.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from server.geometry import beacon_outline_m, beacon_to_world, camera_matrix, distortion_vector, world_to_camera
from shared_schemas import Beacon, BeaconMap, FrameMeta
from shared_schemas.survey import PanelLabel
from simulator.fixtures import write_fixture
from simulator.render import CameraPose
from simulator.scene import Scene, render_sample


@dataclass(frozen=True)
class SurveyShots:
    heights_m: tuple[float, float] = (1.2, 1.6)
    max_tilt_deg: float = 30.0
    aim_jitter_m: float = 0.25
    neighbour_m: float = 1.9  # panels at most this far apart count as neighbours to aim between
    min_label_px: float = 400.0  # visible area (px^2) of a panel for it to be labelled
    true_bearing_deg: float = 30.0  # the compass bearing of the map's +X
    compass_bias_sigma_deg: float = 10.0  # a phone compass indoors: one error for the whole survey ...
    compass_noise_sigma_deg: float = 10.0  # ... plus each frame's own


def _visible_part(beacon: Beacon, scene: Scene, pose: CameraPose) -> np.ndarray | None:
    """The panel's image clipped to the frame (M, 2), or None when it is behind the camera or out of view."""
    camera = scene.camera.intrinsics()
    width, height = scene.camera.frame_size()
    outline = beacon_to_world(beacon, beacon_outline_m(beacon, 8))
    in_camera = world_to_camera(outline, pose.position_m, pose.rotation_wc)
    if np.any(in_camera[:, 2] <= 0.05):
        return None
    pixels, _ = cv2.projectPoints(in_camera, np.zeros(3), np.zeros(3), camera_matrix(camera), distortion_vector(camera))
    frame = np.array([[-0.5, -0.5], [width - 0.5, -0.5], [width - 0.5, height - 0.5], [-0.5, height - 0.5]], np.float32)
    hull = cv2.convexHull(pixels.reshape(-1, 2).astype(np.float32))
    area, part = cv2.intersectConvexConvex(hull, frame)
    return None if part is None or area <= 0 else part.reshape(-1, 2)


def labels_for(scene: Scene, pose: CameraPose, shots: SurveyShots) -> list[PanelLabel]:
    """A label (the centroid of its visible part) for every panel with enough of its image in view."""
    labels = []
    for spec in scene.beacons:
        part = _visible_part(spec.beacon(), scene, pose)
        if part is None or cv2.contourArea(part.astype(np.float32)) < shots.min_label_px:
            continue
        moments = cv2.moments(part.astype(np.float32))
        x, y = moments["m10"] / moments["m00"], moments["m01"] / moments["m00"]
        labels.append(PanelLabel(beacon_id=spec.id, x_px=max(0.0, x), y_px=max(0.0, y)))
    return labels


def _centres_in_view(scene: Scene, pose: CameraPose) -> int:
    camera = scene.camera.intrinsics()
    width, height = scene.camera.frame_size()
    centres = np.array([b.center_m for b in scene.beacons], float)
    in_camera = world_to_camera(centres, pose.position_m, pose.rotation_wc)
    ahead = in_camera[:, 2] > 0.1
    pixels, _ = cv2.projectPoints(in_camera[ahead], np.zeros(3), np.zeros(3), camera_matrix(camera), None)
    pixels = pixels.reshape(-1, 2)
    inside = (pixels[:, 0] > 0) & (pixels[:, 0] < width - 1) & (pixels[:, 1] > 0) & (pixels[:, 1] < height - 1)
    return int(inside.sum())


def _aimed(camera_m: np.ndarray, target_m: np.ndarray, turn_rad: float) -> CameraPose:
    """A camera at `camera_m` looking at `target_m`, turned by `turn_rad` about its optical axis."""
    forward = (target_m - camera_m) / np.linalg.norm(target_m - camera_m)
    helper = np.array([1.0, 0.0, 0.0]) if abs(forward[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    right = np.cross(helper, forward)
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    right, down = math.cos(turn_rad) * right + math.sin(turn_rad) * down, -math.sin(turn_rad) * right + math.cos(
        turn_rad
    ) * down
    return CameraPose(camera_m, np.column_stack([right, down, forward]))


def survey_poses(scene: Scene, count: int, rng: np.random.Generator,
                 shots: SurveyShots = SurveyShots()) -> list[CameraPose]:
    """`count` hand-held camera poses under the scene's panels, each with two or more panel centres in view."""
    centres = np.array([b.center_m for b in scene.beacons], float)
    pairs = [(i, j) for i in range(len(centres)) for j in range(i + 1, len(centres))
             if np.linalg.norm(centres[i, :2] - centres[j, :2]) <= shots.neighbour_m]
    if not pairs:
        raise ValueError(f"scene '{scene.name}' has no two panels within {shots.neighbour_m} m of each other")
    low = np.asarray(scene.room.origin_m)[:2]
    high = low + np.asarray(scene.room.size_m)[:2]
    poses: list[CameraPose] = []
    for _ in range(200 * count):
        if len(poses) == count:
            break
        i, j = pairs[int(rng.integers(len(pairs)))]
        target = (centres[i] + centres[j]) / 2 + [*rng.normal(0.0, shots.aim_jitter_m, 2), 0.0]
        height = rng.uniform(*shots.heights_m)
        reach = math.tan(math.radians(shots.max_tilt_deg)) * (target[2] - height)
        offset = rng.uniform(0, reach) * np.array([math.cos(a := rng.uniform(0, 2 * math.pi)), math.sin(a)])
        camera = np.array([target[0] + offset[0], target[1] + offset[1], height])
        if np.any(camera[:2] < low) or np.any(camera[:2] > high):
            continue
        pose = _aimed(camera, target, rng.uniform(-math.pi, math.pi))
        if _centres_in_view(scene, pose) >= 2:
            poses.append(pose)
    if len(poses) < count:
        raise ValueError(f"found only {len(poses)} of {count} survey poses in scene '{scene.name}'")
    return poses


@dataclass(frozen=True)
class SurveyShot:
    pixels: np.ndarray
    meta: FrameMeta
    labels: list[PanelLabel]
    pose: CameraPose


def compass_reading_deg(pose: CameraPose, shots: SurveyShots, rng: np.random.Generator, bias_deg: float = 0.0) -> float:
    """The compass bearing of the image's +x laid level, off by the survey's `bias_deg` and the frame's own
    noise, in [0, 360)."""
    yaw = math.degrees(math.atan2(pose.rotation_wc[1, 0], pose.rotation_wc[0, 0]))
    return (shots.true_bearing_deg - yaw + bias_deg + rng.normal(0.0, shots.compass_noise_sigma_deg)) % 360.0


def compass_readings_deg(poses: list[CameraPose], shots: SurveyShots, rng: np.random.Generator) -> list[float]:
    """The compass readings of one survey's `poses`: one bias drawn for them all, then each frame's noise."""
    bias_deg = rng.normal(0.0, shots.compass_bias_sigma_deg)
    return [compass_reading_deg(pose, shots, rng, bias_deg) for pose in poses]


def render_survey(scene: Scene, poses: list[CameraPose], rng: np.random.Generator,
                  shots: SurveyShots = SurveyShots()) -> list[SurveyShot]:
    """The pose frames of `poses`, with gravity, a compass reading (`compass_readings_deg`) and labels."""
    rendered = []
    for k, (pose, compass) in enumerate(zip(poses, compass_readings_deg(poses, shots, rng), strict=True)):
        pixels, meta = render_sample(scene, pose, rng, t_s=k * 2.0, compass_bearing_deg=compass)
        rendered.append(SurveyShot(pixels, meta, labels_for(scene, pose, shots), pose))
    return rendered


def sketch_of(beacon_map: BeaconMap, anchor: int, rng: np.random.Generator, error_m: float = 0.05,
              yaw_error_deg: float = 5.0) -> BeaconMap:
    """A tape-measure sketch of `beacon_map`: every panel but the anchor moved by a normal error in
    x, y and z and turned by one about Z (the anchor's centre and yaw kept)."""
    beacons = []
    for beacon in beacon_map.beacons:
        if beacon.id != anchor:
            beacon = beacon.model_copy(update={
                "center_m": [float(v) for v in np.asarray(beacon.center_m) + rng.normal(0.0, error_m, 3)],
                "yaw_deg": float(beacon.yaw_deg + rng.normal(0.0, yaw_error_deg)),
            })
        beacons.append(beacon)
    return beacon_map.model_copy(update={"name": f"{beacon_map.name}-sketch", "beacons": beacons})


def survey_set(scene: Scene, frames: int, rng: np.random.Generator, sketch_error_m: float = 0.05,
               sketch_yaw_error_deg: float = 5.0) -> tuple[BeaconMap, BeaconMap, int, list[SurveyShot]]:
    """(true map, sketch, anchor ID, shots): `frames` rendered survey frames of `scene` and a tape-measure
    sketch of its map, anchored at its first panel."""
    shots = render_survey(scene, survey_poses(scene, frames, rng), rng)
    truth = scene.beacon_map()
    anchor = truth.beacons[0].id
    return truth, sketch_of(truth, anchor, rng, sketch_error_m, sketch_yaw_error_deg), anchor, shots


def write_survey_fixtures(folder: Path, shots: list[SurveyShot], sketch: BeaconMap,
                          frames_folder: Path | None = None) -> tuple[list[Path], Path, Path]:
    """The shots as `lumipose survey` reads them: fixtures `frame_NN.json` + `.y` (in `frames_folder`, default
    `folder`), `labels.json` (a frame's file name -> its labels) and the sketch `sketch.json`; (frame JSON
    paths, labels path, sketch path)."""
    frames_folder = folder if frames_folder is None else frames_folder
    folder.mkdir(parents=True, exist_ok=True)
    frames_folder.mkdir(parents=True, exist_ok=True)
    frames = [write_fixture(frames_folder / f"frame_{k:02d}", shot.pixels, shot.meta)[1]
              for k, shot in enumerate(shots)]
    labels = {path.name: [label.model_dump() for label in shot.labels]
              for path, shot in zip(frames, shots, strict=True)}
    labels_path, sketch_path = folder / "labels.json", folder / "sketch.json"
    labels_path.write_text(json.dumps(labels, indent=1) + "\n")
    sketch_path.write_text(sketch.model_dump_json(by_alias=True, exclude_none=True, indent=2) + "\n")
    return frames, labels_path, sketch_path
