"""The scene spec: room, beacons, camera, sensor, other light, and the sampling series.

A `Scene` is saved as JSON beside every sample so that a session can be reproduced exactly
(the paper, Section II-A: "the resulting samples should include all the data needed to
reproduce the same sampling session"). `render_sample` turns a scene and one camera pose into
an 8-bit luma frame and the contract's frame metadata with ground truth.

Photometry, kept simple and explicit: a surface of luminance L (cd/m^2) gives
L * exposure_s * (iso / 100) * dn_per_nit_s DN before clipping. With the defaults a 1000 cd/m^2
panel at 10 ms and ISO 100 reaches 1020 DN, four times the 8-bit saturation (the contract's
"an LED panel still saturates at minimum ISO and 10 ms"). Gain scales shot noise (fewer
electrons per DN) and read noise.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Annotated, Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from server.camera import intrinsics_from_profile
from server.geometry import beacon_to_world, dense_beacon_outline_m, rotation_from_ypr, world_to_camera
from server.vlc.capture import ID_EXPOSURE_S
from server.vlc.codec import DEFAULT_DEPTH
from shared_schemas import Beacon, BeaconMap, CameraIntrinsics, FrameMeta, GroundTruth, PanelShape, device_profiles
from shared_schemas.cli import describe_file_error
from shared_schemas.models import Facing, Strict, Vec3
from simulator.chain import ChainSpec, circle_of_confusion_px, develop
from simulator.motion import MotionSpec, draw_velocities
from simulator.panels import PanelSpec, panel_emitters
from simulator.render import (
    CameraPose,
    Emitter,
    ReadoutMotion,
    SensorModel,
    exposure_polygons_px,
    render_emitters,
    render_signal,
)

SCENE_SCHEMA = "lumipose.scene/1"
SCENES_DIR = Path(__file__).parent / "scenes"
Positive = Annotated[float, Field(gt=0)]


def _finite(name: str, values) -> None:
    for value in np.ravel(values):
        if not math.isfinite(value):
            raise ValueError(f"{name} must be finite numbers, got {value}")


class RoomSpec(Strict):
    """The room as a box from `origin_m` (a floor corner) to `origin_m + size_m`; beacons hang in it."""

    size_m: Vec3 = Field(description="x, y and height of the room, metres")
    origin_m: Vec3 = Field(default=[0.0, 0.0, 0.0], description="the floor corner with the smallest x, y")

    @field_validator("size_m")
    @classmethod
    def _positive(cls, value: list[float]) -> list[float]:
        if any(not (math.isfinite(v) and v > 0) for v in value):
            raise ValueError(f"size_m must be three positive numbers, got {value}")
        return value


DEFAULT_SIDE_M = 0.174  # the paper's panel


class BeaconSpec(Strict):
    """A map beacon (`shared_schemas.Beacon`) with its light; a 0.174 m square unless its shape
    or size is given."""

    id: int = Field(ge=0, le=255)
    center_m: Vec3
    yaw_deg: float = 0.0
    shape: PanelShape = PanelShape.rounded_rectangle
    side_m: Positive | None = None
    width_m: Positive | None = None
    height_m: Positive | None = None
    diameter_m: Positive | None = None
    corner_radius_m: float = Field(default=0.02, ge=0)
    luminance_nits: Positive = 1000.0
    vlc_code: int | None = Field(default=None, ge=0, le=255,
                                 description="the code the panel blinks (normally its id); none = steady light")
    vlc_phase_s: float = Field(default=0.0, description="the message start on the LED's clock")
    vlc_depth: float = Field(default=DEFAULT_DEPTH, ge=0.0, le=1.0,
                             description="modulation depth: a 0 chip is 1 - depth of a 1 chip (1.0: the LED off)")
    panel: PanelSpec | None = Field(
        default=None, description="bezel, edge fall-off, glossy ceiling (simulator.panels); none: the bare panel")

    def beacon(self) -> Beacon:
        sizes = {name: getattr(self, name) for name in ("side_m", "width_m", "height_m", "diameter_m")}
        if self.shape is PanelShape.rounded_rectangle and all(v is None for v in sizes.values()):
            sizes["side_m"] = DEFAULT_SIDE_M
        radius = 0.0 if self.shape is PanelShape.circle else self.corner_radius_m
        return Beacon(id=self.id, center_m=self.center_m, yaw_deg=self.yaw_deg, shape=self.shape,
                      corner_radius_m=radius, **{k: v for k, v in sizes.items() if v is not None})

    @property
    def size_m(self) -> float:
        return self.beacon().size_m

    @model_validator(mode="after")
    def _geometry(self) -> BeaconSpec:
        self.beacon()  # the map's own checks: finite centre, radius < side / 2
        return self


class CameraSpec(Strict):
    """A device profile (with optional overrides) or a general camera.

    Sizes are the delivered frame's: `scale` of the profile's native size unless `width` and
    `height` are given. `cx`, `cy` default to the frame centre (pixel centres at integers).
    """

    profile: str | None = "xiaomi-mi8-front"
    scale: float = Field(default=1.0, gt=0, le=4)
    width: int | None = Field(default=None, gt=0)
    height: int | None = Field(default=None, gt=0)
    pixel_size_m: float | None = Field(default=None, gt=0, description="native pixel pitch")
    focal_length_m: float | None = Field(default=None, gt=0)
    cx: float | None = None
    cy: float | None = None
    distortion: list[float] | None = Field(default=None, description="OpenCV order; none = the profile's")
    facing: Facing | None = None

    @model_validator(mode="after")
    def _complete(self) -> CameraSpec:
        if self.profile is None:
            missing = [name for name in ("width", "height", "pixel_size_m", "focal_length_m")
                       if getattr(self, name) is None]
            if missing:
                raise ValueError(f"a camera without a profile needs {', '.join(missing)}")
        elif self.profile not in device_profiles():
            raise ValueError(f"unknown device profile '{self.profile}'; known: {', '.join(sorted(device_profiles()))}")
        if (self.width is None) != (self.height is None):
            raise ValueError("give both width and height, or neither")
        if self.distortion is not None:
            CameraIntrinsics(fx=1, fy=1, cx=0, cy=0, distortion=self.distortion)  # shape check, names the field
        return self

    def frame_size(self) -> tuple[int, int]:
        if self.width is not None:
            return self.width, self.height
        profile = device_profiles()[self.profile]
        return round(profile.width * self.scale), round(profile.height * self.scale)

    def intrinsics(self) -> CameraIntrinsics:
        width, height = self.frame_size()
        if self.profile is not None:
            profile = device_profiles()[self.profile]
            updates = {k: getattr(self, k) for k in ("pixel_size_m", "focal_length_m") if getattr(self, k) is not None}
            profile = profile.model_copy(update=updates)
            camera = intrinsics_from_profile(profile, width, height)
        else:
            focal_px = self.focal_length_m / self.pixel_size_m
            camera = CameraIntrinsics(fx=focal_px, fy=focal_px, cx=(width - 1) / 2, cy=(height - 1) / 2,
                                      pixel_size_m=self.pixel_size_m, focal_length_m=self.focal_length_m)
        updates = {k: getattr(self, k) for k in ("cx", "cy", "distortion") if getattr(self, k) is not None}
        return camera.model_copy(update=updates) if updates else camera


class SensorSpec(Strict):
    exposure_s: Positive = 0.01
    iso: float = Field(default=100.0, ge=25, le=12800)
    black_level_dn: float = Field(default=4.0, ge=0)
    ambient_nits: float = Field(default=4.0, ge=0, description="diffuse room light seen everywhere")
    dn_per_nit_s: Positive = 102.0
    psf_sigma_px: float = Field(default=1.0, ge=0)
    electrons_per_dn_iso100: Positive = 16.0
    read_noise_dn_iso100: float = Field(default=1.5, ge=0)
    vignetting: float = Field(default=0.0, ge=0, lt=1, description="light lost at the image corner")
    rolling_shutter_skew_s: float = Field(default=0.03, ge=0, description="first to last row's exposure start")

    @property
    def gain(self) -> float:
        return self.iso / 100.0

    def dn_per_nit(self) -> float:
        return self.exposure_s * self.gain * self.dn_per_nit_s

    def model(self) -> SensorModel:
        return SensorModel(
            background_dn=self.black_level_dn + self.ambient_nits * self.dn_per_nit(),
            plateau_dn=0.0,  # each emitter carries its own level
            psf_sigma_px=self.psf_sigma_px,
            electrons_per_dn=self.electrons_per_dn_iso100 / self.gain,
            read_noise_dn=self.read_noise_dn_iso100 * self.gain,
            vignetting=self.vignetting,
        )


class IdFramesSpec(Strict):
    """The ID frames of the scene's bursts (`lumipose simulate --bursts`, `bench office`): what differs
    from its pose frames, whose sensor and camera are the scene's own (docs/vlc.md, "Capture protocol")."""

    exposure_s: Positive = ID_EXPOSURE_S
    iso: float | None = Field(default=None, ge=25, le=12800,
                              description="none: the pose frame's brightness times the protocol's ID_BRIGHTNESS_FRACTION")
    scale: float | None = Field(default=None, gt=0, le=4, description="of the camera's native size; none: the pose frames'")


class LightSourceSpec(Strict):
    """Another bright thing: a window or lamp (polygon), or a ceiling lamp / reflection (disc)."""

    kind: Literal["polygon", "disc"]
    points_m: list[Vec3] | None = Field(default=None, description="polygon corners, map frame")
    center_m: Vec3 | None = Field(default=None, description="disc centre; the disc is horizontal")
    radius_m: float | None = Field(default=None, gt=0)
    luminance_nits: Positive = 300.0
    blur_px: float = Field(default=0.0, ge=0, description="extra blur: a reflection is soft")
    label: str = ""

    @model_validator(mode="after")
    def _shape(self) -> LightSourceSpec:
        if self.kind == "polygon" and (self.points_m is None or len(self.points_m) < 3):
            raise ValueError("a polygon light source needs at least 3 points_m")
        if self.kind == "disc" and (self.center_m is None or self.radius_m is None):
            raise ValueError("a disc light source needs center_m and radius_m")
        return self

    def outline_m(self) -> np.ndarray:
        if self.kind == "polygon":
            return np.asarray(self.points_m, dtype=float)
        angles = np.linspace(0, 2 * np.pi, 96, endpoint=False)
        return np.asarray(self.center_m) + self.radius_m * np.column_stack([np.cos(angles), np.sin(angles),
                                                                            np.zeros_like(angles)])


class RotationSpec(Strict):
    """Attitude of the camera at each sample; all zero = looking straight up, image x = map X."""

    yaw_deg: float = 0.0
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    max_tilt_deg: float = Field(default=0.0, ge=0, le=60, description="random tilt, uniform in [0, max], any direction")
    yaw_jitter_deg: float = Field(default=0.0, ge=0, le=45, description="random yaw, uniform in +-jitter")
    shake_deg: float = Field(default=0.0, ge=0, le=10, description="hand shake RMS per angle (smooth in time)")
    face_walking_direction: bool = Field(default=False, description="trajectories: yaw follows the walk")


class PoseSpec(Strict):
    position_m: Vec3
    ypr_deg: Vec3 = [0.0, 0.0, 0.0]
    t_s: float = 0.0
    velocity_mps: Vec3 = Field(default=[0.0, 0.0, 0.0], description="during readout (rolling shutter), map frame")
    angular_velocity_dps: Vec3 = Field(default=[0.0, 0.0, 0.0], description="during readout, map frame")


class PosesSeries(Strict):
    kind: Literal["poses"] = "poses"
    poses: list[PoseSpec] = Field(min_length=1)


class FovGridSeries(Strict):
    """The paper's grid (eqs. 1-7) under one beacon: camera at each cell corner, `height_m` up."""

    kind: Literal["fov_grid"] = "fov_grid"
    beacon_id: int | None = Field(default=None, description="default: the first beacon")
    height_m: float = 0.0
    cell_m: Positive = 0.05


class GridSeries(Strict):
    """Any rectangular grid: x and y as [start, stop, step] (stop included), camera at `height_m`."""

    kind: Literal["grid"] = "grid"
    x_m: Annotated[list[float], Field(min_length=3, max_length=3)]
    y_m: Annotated[list[float], Field(min_length=3, max_length=3)]
    height_m: float = 0.0

    @model_validator(mode="after")
    def _steps(self) -> GridSeries:
        for name in ("x_m", "y_m"):
            start, stop, step = getattr(self, name)
            _finite(name, [start, stop, step])
            if step <= 0 or stop < start:
                raise ValueError(f"{name} must be [start, stop, step] with step > 0 and stop >= start")
        return self


class TrajectorySeries(Strict):
    """A walk (Figs. 17-18): zig-zag or converging square spiral over `area_m`, or waypoints."""

    kind: Literal["zigzag", "spiral", "waypoints"]
    area_m: Annotated[list[float], Field(min_length=4, max_length=4)] | None = Field(
        default=None, description="x_min, y_min, x_max, y_max")
    spacing_m: Positive = 0.6
    points_m: list[Annotated[list[float], Field(min_length=2, max_length=3)]] | None = None
    speed_mps: Positive = 0.8
    frame_interval_s: Positive = 0.5
    height_m: float = 1.32

    @model_validator(mode="after")
    def _path(self) -> TrajectorySeries:
        if self.kind == "waypoints" and not self.points_m:
            raise ValueError("a waypoints series needs points_m")
        if self.kind != "waypoints" and self.area_m is None:
            raise ValueError(f"a {self.kind} series needs area_m")
        return self


Series = Annotated[PosesSeries | FovGridSeries | GridSeries | TrajectorySeries, Field(discriminator="kind")]


class SeriesSpec(Strict):
    path: Series
    rotation: RotationSpec = RotationSpec()


class Scene(Strict):
    schema_: Literal["lumipose.scene/1"] = Field(default=SCENE_SCHEMA, alias="schema")
    name: str = Field(min_length=1, pattern=r"^[A-Za-z0-9_.-]+$")
    about: str = Field(default="", description="what the scene models and where its numbers come from")
    room: RoomSpec
    beacons: list[BeaconSpec] = Field(min_length=1)
    camera: CameraSpec = CameraSpec()
    sensor: SensorSpec = SensorSpec()
    id_frames: IdFramesSpec = IdFramesSpec()
    light_sources: list[LightSourceSpec] = Field(default_factory=list)
    gravity_sigma_deg: float | None = Field(default=0.1, ge=0, description="gravity sensor error; none = no gravity")
    series: SeriesSpec | None = None
    seed: int = Field(default=0, ge=0)
    chain: ChainSpec | None = Field(
        default=None, description="a phone's image chain (simulator.chain); none = the renderer's 8-bit noise model")

    model_config = {"extra": "forbid", "populate_by_name": True}

    @model_validator(mode="after")
    def _consistent(self) -> Scene:
        ids = [b.id for b in self.beacons]
        if len(ids) != len(set(ids)):
            raise ValueError(f"beacon ids must be unique, got {sorted(ids)}")
        low = np.asarray(self.room.origin_m)
        high = low + self.room.size_m
        for b in self.beacons:
            if np.any(np.asarray(b.center_m) < low - 1e-9) or np.any(np.asarray(b.center_m) > high + 1e-9):
                raise ValueError(f"beacon {b.id} at {b.center_m} is outside the room {low.tolist()}..{high.tolist()}")
        series = self.series.path if self.series else None
        if isinstance(series, FovGridSeries) and series.beacon_id is not None and series.beacon_id not in ids:
            raise ValueError(f"series.path.beacon_id {series.beacon_id} is not a beacon of the scene")
        return self

    def beacon_map(self) -> BeaconMap:
        return BeaconMap(name=self.name, beacons=[b.beacon() for b in self.beacons])

    def to_json(self) -> str:
        # without a chain or panels the file is what it was before they existed
        exclude = {"chain": True} if self.chain is None else {}
        if all(b.panel is None for b in self.beacons):
            exclude["beacons"] = {"__all__": {"panel"}}
        return self.model_dump_json(by_alias=True, indent=2, exclude=exclude or None) + "\n"


def load_scene(path: Path | str) -> Scene:
    """Read and validate a scene file; pydantic's error names the offending field."""
    return Scene.model_validate_json(Path(path).read_text())


def find_scene(name_or_path: str) -> Scene:
    """A scene file, or a bundled scene by name (`paper-bench`, `office`)."""
    path = Path(name_or_path)
    if not path.exists() and (SCENES_DIR / f"{name_or_path}.json").exists():
        path = SCENES_DIR / f"{name_or_path}.json"
    if not path.exists():
        bundled = ", ".join(sorted(p.stem for p in SCENES_DIR.glob("*.json")))
        raise ValueError(f"scene '{name_or_path}' is neither a file nor a bundled scene ({bundled})")
    try:
        return load_scene(path)
    except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError
        raise ValueError(f"cannot read the scene {describe_file_error(path, error)}") from None


def _beacon_outline_m(beacon: Beacon, camera: CameraIntrinsics, distance_m: float) -> np.ndarray:
    """The panel's outline in map coordinates, arcs fine enough for its size in the frame."""
    span_px = camera.fx * beacon.size_m / max(distance_m, 1e-3)
    return beacon_to_world(beacon, dense_beacon_outline_m(beacon, span_px, 0.5))


def _row_gain(spec: BeaconSpec, sensor: SensorSpec, height: int, t_s: float) -> np.ndarray | None:
    if spec.vlc_code is None:
        return None
    from server.vlc.codec import LedWaveform
    from simulator.led import row_gains

    waveform = LedWaveform.for_beacon(spec.vlc_code, depth=spec.vlc_depth, phase_s=spec.vlc_phase_s)
    row_time_s = sensor.rolling_shutter_skew_s / max(height - 1, 1)
    return row_gains(waveform, height, row_time_s, sensor.exposure_s, t_s)


def readout_motion(scene: Scene, velocity_mps=(0.0, 0.0, 0.0),
                   angular_velocity_dps=(0.0, 0.0, 0.0)) -> ReadoutMotion | None:
    """The rolling shutter's view of a moving camera, or None when it stands still."""
    if not (np.any(velocity_mps) or np.any(angular_velocity_dps)) or scene.sensor.rolling_shutter_skew_s == 0:
        return None
    _, height = scene.camera.frame_size()
    return ReadoutMotion(np.asarray(velocity_mps, dtype=float), np.asarray(angular_velocity_dps, dtype=float),
                         scene.sensor.rolling_shutter_skew_s / max(height - 1, 1), scene.sensor.exposure_s)


def hand_motion(spec: MotionSpec, rng: np.random.Generator, sensor: SensorSpec, rows: int,
                motion: ReadoutMotion | None = None) -> ReadoutMotion | None:
    """`motion` (a walk's, or none) plus velocities drawn from `spec` (`simulator.motion`), read out
    over `rows` rows in the sensor's skew; none when the camera stands still. A still spec draws nothing."""
    velocity, angular = draw_velocities(spec, rng)
    if motion is not None:
        velocity, angular = velocity + motion.velocity_mps, angular + motion.angular_velocity_dps
    if not (np.any(velocity) or np.any(angular)):
        return motion
    return ReadoutMotion(velocity, angular, sensor.rolling_shutter_skew_s / max(rows - 1, 1), sensor.exposure_s)


def readout_on_rows(motion: ReadoutMotion | None, skew_s: float, rows: int) -> ReadoutMotion | None:
    """`motion` read out over `rows` rows in the same skew (a binning sensor has twice the frame's rows)."""
    if motion is None:
        return None
    return dataclasses.replace(motion, row_time_s=skew_s / max(rows - 1, 1))


def defocus_px(chain: ChainSpec | None, camera: CameraIntrinsics, pose: CameraPose, points_m) -> float:
    """`chain`'s defocus disc (pixels of `camera`) for something at the mean of `points_m`."""
    if chain is None or chain.optics.focus_distance_m is None or not camera.focal_length_m:
        return 0.0
    centre = np.mean(np.asarray(points_m, dtype=float).reshape(-1, 3), axis=0)
    depth_m = float(world_to_camera(centre[None, :], pose.position_m, pose.rotation_wc)[0, 2])
    optics = chain.optics
    return circle_of_confusion_px(depth_m, optics.focus_distance_m, optics.f_number, camera.focal_length_m,
                                  camera.focal_length_m / camera.fx)


def scene_emitters(scene: Scene, pose: CameraPose, t_s: float = 0.0, motion: ReadoutMotion | None = None,
                   camera: CameraIntrinsics | None = None, size: tuple[int, int] | None = None) -> list[Emitter]:
    """Every beacon and light source that the camera at `pose` can see, in the frame's pixels
    (or in those of `camera` at `size`, the sensor's own when the chain bins)."""
    camera = camera or scene.camera.intrinsics()
    width, height = size or scene.camera.frame_size()
    per_nit = scene.sensor.dn_per_nit()
    emitters = []
    for spec in scene.beacons:
        distance_m = float(np.linalg.norm(np.subtract(spec.center_m, pose.position_m)))

        def outline_px(beacon: Beacon, distance_m: float = distance_m):
            return exposure_polygons_px(_beacon_outline_m(beacon, camera, distance_m), camera, pose, width, height,
                                        0.5, motion)

        emitters += panel_emitters(spec.beacon(), spec.panel, outline_px, spec.luminance_nits * per_nit,
                                   _row_gain(spec, scene.sensor, height, t_s),
                                   defocus_px(scene.chain, camera, pose, spec.center_m))
    return emitters + light_emitters(scene.light_sources, camera, pose, width, height, per_nit, scene.chain, motion)


def light_emitters(lights: list[LightSourceSpec] | tuple[LightSourceSpec, ...], camera: CameraIntrinsics,
                   pose: CameraPose, width: int, height: int, dn_per_nit: float, chain: ChainSpec | None = None,
                   motion: ReadoutMotion | None = None) -> list[Emitter]:
    """The light sources (a window, a lamp, a reflection) that the camera at `pose` can see, in its pixels."""
    emitters = []
    for light in lights:
        seen = exposure_polygons_px(light.outline_m(), camera, pose, width, height, motion=motion)
        if seen is not None:
            emitters.append(Emitter(seen[0], light.luminance_nits * dn_per_nit, None, light.blur_px,
                                    defocus_px(chain, camera, pose, light.outline_m()), seen[1]))
    return emitters


def gravity_in_camera(rotation_wc: np.ndarray, sigma_deg: float, rng: np.random.Generator) -> list[float]:
    """Gravity (down) in the camera frame as the phone's sensor reports it, tilted by its error."""
    error = rotation_from_ypr(0.0, *rng.normal(0.0, sigma_deg, 2)) if sigma_deg > 0 else np.eye(3)
    return (np.asarray(rotation_wc).T @ error @ np.array([0.0, 0.0, -1.0])).tolist()


def render_sample(scene: Scene, pose: CameraPose, rng: np.random.Generator, t_s: float = 0.0,
                  motion: ReadoutMotion | None = None, **extra) -> tuple[np.ndarray, FrameMeta]:
    """One frame of `scene` from `pose` at time `t_s`: (pixels (height, width) uint8, metadata).

    `pose` is the camera's at `t_s`, the first row's exposure start (Camera2's timestamp);
    with `motion` later rows see it moved. The metadata carries the true intrinsics, exposure,
    ISO, rolling-shutter skew, the gravity sensor's reading and the ground truth (the pose at
    `t_s`); `extra` fields are kept (the contract allows them).
    """
    camera = scene.camera.intrinsics()
    width, height = scene.camera.frame_size()
    if scene.chain is None:
        pixels = render_emitters(scene_emitters(scene, pose, t_s, motion), width, height, scene.sensor.model(), rng)
    else:
        pixels = render_through_chain(scene, pose, rng, t_s, motion)
    gravity = (None if scene.gravity_sigma_deg is None
               else gravity_in_camera(pose.rotation_wc, scene.gravity_sigma_deg, rng))
    meta = FrameMeta(
        width=width, height=height, row_stride=width, camera=camera,
        exposure_s=scene.sensor.exposure_s, iso=scene.sensor.iso,
        rolling_shutter_skew_s=scene.sensor.rolling_shutter_skew_s, timestamp_ns=round(t_s * 1e9),
        gravity_camera=gravity,
        ground_truth=GroundTruth(position_m=[float(v) for v in pose.position_m],
                                 rotation_wc=np.asarray(pose.rotation_wc, dtype=float).tolist()),
        **{"tone_curve": scene.chain.reported_tone_curve() if scene.chain is not None else None, **extra},
    )
    return pixels, meta


def render_through_chain(scene: Scene, pose: CameraPose, rng: np.random.Generator, t_s: float = 0.0,
                         motion: ReadoutMotion | None = None) -> np.ndarray:
    """The frame (height, width) uint8 as `scene.chain`'s phone makes it (`simulator.chain.develop`).

    With 2x2 binning the light is drawn on the sensor's own pixels, twice the frame's size (the
    frame's pixel (i, j) is the mean of sensor pixels 2i, 2i + 1 and 2j, 2j + 1; the PSF's
    `psf_sigma_px` stays in the frame's pixels), and the rolling shutter reads twice the rows.
    The chain's `motion` adds velocities drawn from `rng` to `motion` (not written into the frame's
    metadata).
    """
    width, height = scene.camera.frame_size()
    motion = hand_motion(scene.chain.motion, rng, scene.sensor, height, motion)

    def emitters_for(camera: CameraIntrinsics, size: tuple[int, int]) -> list[Emitter]:
        moved = motion if size[1] == height else readout_on_rows(motion, scene.sensor.rolling_shutter_skew_s, size[1])
        return scene_emitters(scene, pose, t_s, moved, camera, size)

    return develop_emitters(scene.chain, emitters_for, scene.camera.intrinsics(), width, height,
                            scene.sensor.model(), scene.sensor.black_level_dn, rng)


def develop_emitters(chain: ChainSpec, emitters_for, camera: CameraIntrinsics, width: int, height: int,
                     model: SensorModel, black_level_dn: float, rng: np.random.Generator) -> np.ndarray:
    """The frame (height, width) uint8 that `chain` makes of the light of `emitters_for(camera, size)`.

    `emitters_for` gives the emitters in the pixels of the camera and frame size it is handed:
    the frame's, or with 2x2 binning the sensor's own, twice the frame's size (fx, fy x 2,
    c -> 2c + 0.5, the PSF's sigma doubled so that it stays the same in the frame's pixels).
    """
    if chain.pixels.binning == 2:
        camera = camera.model_copy(update={
            "fx": 2 * camera.fx, "fy": 2 * camera.fy, "cx": 2 * camera.cx + 0.5, "cy": 2 * camera.cy + 0.5,
            "pixel_size_m": camera.pixel_size_m / 2 if camera.pixel_size_m else None})
        width, height = 2 * width, 2 * height
        model = dataclasses.replace(model, psf_sigma_px=2 * model.psf_sigma_px)
    signal = render_signal(emitters_for(camera, (width, height)), width, height, model)
    return develop_signal(chain, signal, camera, model, black_level_dn, rng)


def develop_signal(chain: ChainSpec, signal_dn: np.ndarray, camera: CameraIntrinsics, model: SensorModel,
                   black_level_dn: float, rng: np.random.Generator) -> np.ndarray:
    """`simulator.chain.develop` of the noiseless light `signal_dn` in the pixels of `camera`, at the sensor
    `model`'s gain, read noise and saturation (the halo's width from the camera's focal length)."""
    halo_sigma_px = camera.fx * math.tan(math.radians(chain.optics.halo_sigma_deg))
    return develop(signal_dn, chain, electrons_per_dn=model.electrons_per_dn, read_noise_dn=model.read_noise_dn,
                   black_level_dn=black_level_dn, halo_sigma_px=halo_sigma_px, rng=rng,
                   saturation_dn=model.saturation_dn)
