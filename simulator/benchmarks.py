"""`lumipose bench accuracy` and `lumipose bench speed`: figures, not tests.

Accuracy: frames rendered at the paper's test-bench geometry (Xiaomi Mi 8 front camera,
0.174 m panel with 0.02 m corner radius), camera positions drawn uniformly over the
beacon-adjusted FOV (paper eq. 4) at each distance, tilts up to `max_tilt_deg`, yaw within
the contract's +-45 degree rule, PSF and overexposure drawn per frame. Poses whose panel
leaves the frame are drawn again (a cut-off panel is refused, and is another benchmark's
subject). Each frame is located three ways: vision only, gravity prior always, and auto.

Speed: the whole pipeline on one full-resolution frame against one `cv2.threshold` pass over
the same frame, both timed in the same run.
"""

from __future__ import annotations

import math
import os
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np

from server.camera import intrinsics_from_profile
from server.fov import fov_grid
from server.geometry import (
    angle_deg, beacon_to_world, dense_beacon_outline_m, gravity_in_camera, rotation_from_ypr, world_to_camera,
)
from server.ingest import LumaFrame
from server.locator import locate
from server.options import LocateOptions
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from shared_schemas import Beacon, BeaconMap, device_profiles
from simulator.bench_results import frame_outcome
from simulator.chain import ChainSpec
from simulator.fixtures import fixture_meta
from simulator.panels import PanelSpec, panel_emitters
from simulator.scene import (
    LightSourceSpec, SensorSpec, defocus_px, develop_emitters, hand_motion, light_emitters, readout_on_rows,
)
from simulator.render import (
    CameraPose, Emitter, ReadoutMotion, SensorModel, beacon_outline_px, exposure_polygons_px, render_emitters,
    render_frame,
)

PROFILE_ID = "xiaomi-mi8-front"
MODES = {"vision": GravityMode.never, "gravity": GravityMode.always, "auto": GravityMode.auto}
CHI2_2DOF_95 = 5.991  # a 2D Gaussian error lies inside d^T C^-1 d <= 5.991 with probability 95 %
BENCH_PANEL_NITS = 1000.0  # the bench's panel is the scene default's 1000 cd/m2: light sources scale its level


@dataclass(frozen=True)
class AccuracyConfig:
    distance_m: float = 1.0
    frames: int = 200
    scale: float = 1.0  # of the profile's native resolution
    max_tilt_deg: float = 10.0
    max_yaw_deg: float = 40.0
    psf_sigma_px: tuple[float, float] = (0.8, 1.5)
    overexposure: tuple[float, float] = (2.0, 6.0)  # plateau / saturation
    gravity_sigma_deg: float = 0.1
    seed: int = 1
    renderer: str = "ours"  # or "blender": Cycles' radiance through the same sensor (simulator.blender)
    # a phone's image chain (simulator.chain) instead of the renderer's 8-bit noise; with blender, a still one
    chain: ChainSpec | None = None
    black_level_dn: float = 4.0  # the chain's black level (SensorSpec's default; the background stays 8 DN)
    panel: PanelSpec | None = None  # bezel, edge fall-off, glossy ceiling (simulator.panels); ours only
    light_sources: tuple[LightSourceSpec, ...] = ()  # a second lamp, a window (map frame: the panel at z = distance)


RENDERERS = ("ours", "blender")
BENCH_SENSOR = SensorSpec()  # its 10 ms exposure (as `fixture_meta` records) and 30 ms rolling-shutter skew


def bench_beacon(distance_m: float) -> Beacon:
    return Beacon(id=0, center_m=[0.0, 0.0, distance_m], yaw_deg=0.0, side_m=0.174, corner_radius_m=0.02)


def noisy_gravity(rotation_wc: np.ndarray, sigma_deg: float, rng: np.random.Generator) -> list[float]:
    """Gravity (down) in the camera frame, tilted by a random error of `sigma_deg` per axis."""
    error = rotation_from_ypr(0.0, *rng.normal(0.0, sigma_deg, 2))
    return (rotation_wc.T @ error @ np.array([0.0, 0.0, -1.0])).tolist()


def _draw_pose(config: AccuracyConfig, beacon: Beacon, camera, width, height, rng) -> CameraPose:
    profile = device_profiles()[PROFILE_ID]
    extent = fov_grid(profile, config.distance_m, 0.05, beacon.size_m).beacon_adjusted_m
    margin_px = 8.0
    while True:
        xy = rng.uniform(-0.5, 0.5, 2) * extent
        tilt = rng.uniform(0.0, config.max_tilt_deg)
        azimuth = rng.uniform(0.0, 2 * math.pi)
        yaw = rng.uniform(-config.max_yaw_deg, config.max_yaw_deg)
        rotation = rotation_from_ypr(yaw, tilt * math.cos(azimuth), tilt * math.sin(azimuth))
        pose = CameraPose(position_m=np.array([xy[0], xy[1], 0.0]), rotation_wc=rotation)
        outline = beacon_outline_px(beacon, camera, pose)
        inside = (outline.min(axis=0) > margin_px).all() and (outline.max(axis=0) < [width - margin_px, height - margin_px]).all()
        if inside:
            return pose


def accuracy_frame(config: AccuracyConfig, index: int) -> tuple[LumaFrame, BeaconMap, CameraPose]:
    """Frame `index` of the accuracy benchmark at `config` (the same for the same seed), its map
    and the camera's true pose."""
    rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000)])
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * config.scale), round(profile.height * config.scale)
    camera = intrinsics_from_profile(profile, width, height)
    beacon = bench_beacon(config.distance_m)
    pose = _draw_pose(config, beacon, camera, width, height, rng)
    sensor = SensorModel(
        psf_sigma_px=rng.uniform(*config.psf_sigma_px),
        plateau_dn=255.0 * rng.uniform(*config.overexposure),
    )
    motion = bench_motion(config, index, height)
    if config.renderer == "blender" and (config.panel is not None or config.light_sources):
        raise ValueError("a panel spec or light sources go with renderer 'ours' only")
    # the chain's noise from its own generator: every chain sees the same pose, PSF, level and gravity draws
    chain_rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000), 13])
    if config.chain is not None and config.renderer == "ours":
        pixels = chain_frame(config.chain, beacon, camera, pose, width, height, sensor, config.black_level_dn,
                             chain_rng, motion, config.panel, config.light_sources)
    elif config.renderer == "blender":
        from simulator.blender import render_blender_chain_frame, render_blender_frame  # bpy is an optional extra

        pixels = (render_blender_frame(beacon, camera, pose, width, height, sensor, rng) if config.chain is None
                  else render_blender_chain_frame(beacon, camera, pose, width, height, sensor, config.chain,
                                                  config.black_level_dn, chain_rng))
    elif config.renderer == "ours":
        pixels = render_emitters(bench_emitters(beacon, camera, pose, (width, height), sensor, None, config.panel,
                                                config.light_sources), width, height, sensor, rng)
    else:
        raise ValueError(f"renderer must be one of {RENDERERS}, got {config.renderer!r}")
    meta = fixture_meta(camera, width, height, pose,
                        gravity_camera=noisy_gravity(pose.rotation_wc, config.gravity_sigma_deg, rng),
                        tone_curve=config.chain.reported_tone_curve() if config.chain is not None else None,
                        **({} if motion is None else gyroscope_meta(motion, pose, config, index)))
    return LumaFrame(pixels=pixels, meta=meta, camera=camera), BeaconMap(name="bench", beacons=[beacon]), pose


def bench_motion(config: AccuracyConfig, index: int, rows: int) -> ReadoutMotion | None:
    """The camera's motion during frame `index` (`config.chain.motion`, `simulator.motion`), drawn from the
    frame's own generator, so that every cell sees the same poses and noise; none when it stands still."""
    if config.chain is None or config.chain.motion.still:
        return None
    rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000), 14])
    return hand_motion(config.chain.motion, rng, BENCH_SENSOR, rows)


GYRO_BIAS_DPS = 0.1  # a phone gyroscope's residual bias after Android's calibration, per axis (an assumption)


def gyroscope_meta(motion: ReadoutMotion, pose: CameraPose, config: AccuracyConfig, index: int) -> dict:
    """What the app reports of a moving frame: the readout's skew and the gyroscope's rate in the camera
    frame (the drawn turn, R^T omega, with a bias of GYRO_BIAS_DPS per axis from the frame's own generator)."""
    rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000), 15])
    rate = pose.rotation_wc.T @ np.asarray(motion.angular_velocity_dps) + rng.normal(0.0, GYRO_BIAS_DPS, 3)
    return {"rolling_shutter_skew_s": BENCH_SENSOR.rolling_shutter_skew_s, "angular_velocity_camera_dps": rate.tolist()}


def position_seen_m(pose: CameraPose, motion: ReadoutMotion | None, camera, point_m) -> np.ndarray:
    """Where the camera is when the rolling shutter sees `point_m` (the middle of its row's exposure)."""
    if motion is None:
        return np.asarray(pose.position_m, dtype=float)
    in_camera = world_to_camera(np.asarray(point_m, dtype=float)[None, :], pose.position_m, pose.rotation_wc)[0]
    row = camera.fy * in_camera[1] / in_camera[2] + camera.cy
    return np.asarray(pose.position_m, dtype=float) + motion.time_of_row(row) * np.asarray(motion.velocity_mps)


def chain_frame(chain: ChainSpec, beacon: Beacon, camera, pose: CameraPose, width: int, height: int,
                sensor: SensorModel, black_level_dn: float, rng: np.random.Generator,
                motion: ReadoutMotion | None = None, panel: PanelSpec | None = None,
                light_sources: tuple[LightSourceSpec, ...] = ()) -> np.ndarray:
    """The panel's frame as `chain`'s phone makes it (`simulator.scene.develop_emitters`), the panel
    defocused by the thin lens's disc for its depth when the chain sets a focus distance, and with
    `motion` (read out over `height` rows) skewed and blurred as `simulator.scene.scene_emitters` draws it."""
    def emitters_for(cam, size) -> list[Emitter]:
        return bench_emitters(beacon, cam, pose, size, sensor, chain, panel, light_sources, motion, height)

    return develop_emitters(chain, emitters_for, camera, width, height, sensor, black_level_dn, rng)


def bench_emitters(beacon: Beacon, camera, pose: CameraPose, size: tuple[int, int], sensor: SensorModel,
                   chain: ChainSpec | None = None, panel: PanelSpec | None = None,
                   light_sources: tuple[LightSourceSpec, ...] = (), motion: ReadoutMotion | None = None,
                   frame_rows: int | None = None) -> list[Emitter]:
    """The bench's panel at `sensor.plateau_dn` as `panel` draws it, then `light_sources` (a light of L cd/m2
    at L / BENCH_PANEL_NITS of the panel's level), in the pixels of `camera` at `size`; with `motion` (read
    out over the frame's `frame_rows`) skewed and blurred as `simulator.scene.scene_emitters` draws it."""
    on_rows = None if motion is None else readout_on_rows(motion, motion.row_time_s * max((frame_rows or 1) - 1, 1),
                                                          size[1])

    def outline_px(b: Beacon):
        if on_rows is None:
            return beacon_outline_px(b, camera, pose), ()
        distance_m = float(np.linalg.norm(np.subtract(b.center_m, pose.position_m)))
        outline_m = beacon_to_world(b, dense_beacon_outline_m(b, camera.fx * b.size_m / max(distance_m, 1e-3), 0.5))
        return exposure_polygons_px(outline_m, camera, pose, size[0], size[1], 0.5, on_rows)

    emitters = panel_emitters(beacon, panel, outline_px, sensor.plateau_dn,
                              defocus_px=defocus_px(chain, camera, pose, beacon.center_m))
    return emitters + light_emitters(light_sources, camera, pose, *size, sensor.plateau_dn / BENCH_PANEL_NITS, chain,
                                     on_rows)


def _accuracy_sample(args: tuple[AccuracyConfig, int]) -> dict:
    config, index = args
    frame, beacon_map, pose = accuracy_frame(config, index)
    errors, outcomes = {}, {}
    for mode, gravity_mode in MODES.items():
        options = PipelineOptions(gravity_mode=gravity_mode, gravity_sigma_deg=config.gravity_sigma_deg)
        result = locate(frame, beacon_map, LocateOptions(pipeline=options))
        outcomes[mode] = frame_outcome(result)
        if result.ok:
            delta = np.subtract(result.position_m, pose.position_m)
            errors[mode] = (float(np.hypot(*delta[:2])), float(np.linalg.norm(delta)),
                            _tilt_error_deg(np.asarray(result.rotation_wc), pose.rotation_wc),
                            *ellipse_test(delta[:2], result.position_covariance_m2))
        else:
            errors[mode] = (math.nan, math.nan, result.reason.value, None, None)
    return {"index": index, "errors": errors, "outcomes": outcomes}


def ellipse_test(delta_xy, covariance_m2) -> tuple[bool | None, float | None]:
    """(is the 2D error `delta_xy` inside the reported 95 % ellipse, the reported 2D sigma (m)).

    The ellipse is the XY block C of the position's covariance: inside when
    d^T C^-1 d <= 5.991 (chi-square, 2 dof, 95 %). The 2D sigma is sqrt(trace C), the RMS
    horizontal error the covariance predicts. (None, None) without a covariance.
    """
    if covariance_m2 is None:
        return None, None
    block = np.asarray(covariance_m2, dtype=float)[:2, :2]
    d = np.asarray(delta_xy, dtype=float)
    try:
        inside = float(d @ np.linalg.solve(block, d)) <= CHI2_2DOF_95
    except np.linalg.LinAlgError:
        inside = False
    return bool(inside), float(np.sqrt(max(np.trace(block), 0.0)))


def calibration(tests: list[tuple[bool | None, float | None]]) -> dict:
    """Share (%) of fixes whose 2D error is inside their reported 95 % ellipse, and the mean
    reported 2D sigma (mm), over the fixes that carry a covariance (`ellipse_test`'s results).
    A calibrated covariance puts ~95 % inside; fewer means it claims too much."""
    known = [(inside, sigma) for inside, sigma in tests if inside is not None and sigma is not None]
    if not known:
        return {}
    return {"ellipse95_pct": 100.0 * sum(inside for inside, _ in known) / len(known),
            "mean_sigma_2d_mm": 1000.0 * float(np.mean([sigma for _, sigma in known])),
            "with_covariance": len(known)}


def _tilt_error_deg(rotation_wc: np.ndarray, truth_wc: np.ndarray) -> float:
    """Angle between the estimated and the true down direction in the camera (pitch and roll)."""
    return angle_deg(gravity_in_camera(rotation_wc), gravity_in_camera(truth_wc))


def summarize(errors_m: list[float]) -> dict:
    """Mean, std, min, max, p95 (mm) and coverage (%) of 2D errors; NaN = no fix."""
    found = np.array([e for e in errors_m if math.isfinite(e)]) * 1000.0
    if len(found) == 0:
        return {"coverage_pct": 0.0}
    return {
        "mean_mm": float(found.mean()),
        "std_mm": float(found.std()),
        "min_mm": float(found.min()),
        "max_mm": float(found.max()),
        "p95_mm": float(np.percentile(found, 95)),
        "coverage_pct": 100.0 * len(found) / len(errors_m),
    }


def progress(done: int, total: int, label: str) -> None:
    """`label: done/total` on stderr: in place on a terminal, every tenth on a line of its own in a log."""
    if sys.stderr.isatty():
        print(f"\r{label}: {done}/{total}", end="\n" if done == total else "", file=sys.stderr, flush=True)
    elif done == total or done % max(1, total // 10) == 0:
        print(f"{label}: {done}/{total}", file=sys.stderr, flush=True)


def run_accuracy(config: AccuracyConfig, workers: int | None = None) -> dict:
    """Render and locate `config.frames` frames; summaries per gravity mode."""
    workers = workers or os.cpu_count() or 1
    samples = []
    label = f"accuracy at {config.distance_m:.1f} m ({config.renderer})"
    with ProcessPoolExecutor(max_workers=workers) as pool:
        for sample in pool.map(_accuracy_sample, [(config, i) for i in range(config.frames)], chunksize=2):
            samples.append(sample)
            progress(len(samples), config.frames, label)
    summary = {}
    for mode in MODES:
        summary[mode] = summarize([s["errors"][mode][0] for s in samples])
        failed = [s["errors"][mode] for s in samples if isinstance(s["errors"][mode][2], str)]
        located = [s["errors"][mode] for s in samples if not isinstance(s["errors"][mode][2], str)]
        summary[mode]["refusals"] = sorted({e[2] for e in failed})
        summary[mode]["mean_3d_mm"] = float(np.nanmean([s["errors"][mode][1] for s in samples]) * 1000.0)
        tilts = [e[2] for e in located]
        if tilts:
            summary[mode]["mean_tilt_error_deg"] = float(np.mean(tilts))
            summary[mode]["p95_tilt_error_deg"] = float(np.percentile(tilts, 95))
        summary[mode].update(calibration([(e[3], e[4]) for e in located]))
    return {"distance_m": config.distance_m, "frames": config.frames, "scale": config.scale,
            "renderer": config.renderer, "gravity_sigma_deg": config.gravity_sigma_deg, "modes": summary,
            "outcomes": [{"index": s["index"], **s["outcomes"]} for s in samples]}  # per mode, for `bench results`


def renderer_ratios(reports: list[dict], mode: str = "auto") -> list[dict]:
    """Blender's mean error over ours at each distance, from reports of both renderers on the same frames."""
    means = {(r["distance_m"], r["renderer"]): r["modes"][mode].get("mean_mm") for r in reports}
    ratios = []
    for distance in sorted({d for d, _ in means}):
        ours, blender = means.get((distance, "ours")), means.get((distance, "blender"))
        if ours and blender is not None:
            ratios.append({"distance_m": distance, "mode": mode, "ours_mean_mm": ours, "blender_mean_mm": blender,
                           "ratio": blender / ours})
    return ratios


def run_speed_over_frames(frames: int = 10, distances_m: tuple[float, ...] = (1.0, 2.0, 3.0), rounds: int = 5,
                          seed: int = 1) -> dict:
    """The pipeline's time against one `cv2.threshold` pass of the same frame, over many frames.

    The accuracy benchmark's frames (`frames` per distance, full resolution, tilts and yaws drawn,
    gravity with its sensor error), each timed once per round, the threshold pass just before
    the pipeline on the same frame; `rounds` passes over all of them. The ratio is the median of
    the per-frame ratios; each round's median shows how much the machine moved it.
    """
    scenes = [accuracy_frame(AccuracyConfig(distance_m=d, seed=seed), i)[:2]
              for d in distances_m for i in range(frames)]
    for frame, beacon_map in scenes:
        locate(frame, beacon_map)  # warm-up: first calls allocate
    ratios: list[list[float]] = []
    pipeline_ms: list[float] = []
    refusals = 0
    for _ in range(rounds):
        ratios.append([])
        for frame, beacon_map in scenes:
            start = time.perf_counter()
            cv2.threshold(frame.pixels, 128, 255, cv2.THRESH_BINARY)
            threshold = time.perf_counter() - start
            start = time.perf_counter()
            result = locate(frame, beacon_map)
            elapsed = time.perf_counter() - start
            refusals += not result.ok
            pipeline_ms.append(elapsed * 1000.0)
            ratios[-1].append(elapsed / threshold)
    every = [r for round_ratios in ratios for r in round_ratios]
    return {
        "frames": len(scenes),
        "distances_m": list(distances_m),
        "rounds": rounds,
        "median_ratio_to_threshold": statistics.median(every),
        "round_median_ratios": [statistics.median(r) for r in ratios],
        "p90_ratio": float(np.percentile(every, 90)),
        "median_ms": statistics.median(pipeline_ms),
        "refusals": refusals,
        "cv2_threads": cv2.getNumThreads(),
        "cpu_count": os.cpu_count(),
    }


def run_speed(repeats: int = 50, distance_m: float = 1.0, seed: int = 7, gravity: bool = True) -> dict:
    """Median pipeline time on a full-resolution frame, and its ratio to one threshold pass.

    With `gravity` the frame carries the phone's gravity vector, as a phone sends it, so the
    default pose path (the MAP fit with the gravity prior) is what is timed.
    """
    profile = device_profiles()[PROFILE_ID]
    width, height = profile.width, profile.height
    camera = intrinsics_from_profile(profile, width, height)
    beacon = bench_beacon(distance_m)
    rng = np.random.default_rng(seed)
    pose = CameraPose(position_m=np.array([0.12, -0.2, 0.0]), rotation_wc=rotation_from_ypr(10.0, 3.0, -2.0))
    pixels = render_frame(beacon, camera, pose, width, height, SensorModel(psf_sigma_px=1.0), rng)
    down = (pose.rotation_wc.T @ np.array([0.0, 0.0, -1.0])).tolist() if gravity else None
    frame = LumaFrame(pixels=pixels, meta=fixture_meta(camera, width, height, pose, gravity_camera=down), camera=camera)
    beacon_map = BeaconMap(name="bench", beacons=[beacon])
    pipeline_ms, threshold_ms, stages = [], [], []
    locate(frame, beacon_map)  # warm-up: first calls allocate
    for _ in range(repeats):
        start = time.perf_counter()
        cv2.threshold(pixels, 128, 255, cv2.THRESH_BINARY)
        threshold_ms.append((time.perf_counter() - start) * 1000.0)
        start = time.perf_counter()
        result = locate(frame, beacon_map)
        pipeline_ms.append((time.perf_counter() - start) * 1000.0)
        stages.append(result.timing_ms)
    if not result.ok:
        raise RuntimeError(f"speed benchmark frame gave no fix: {result.message}")
    median_ms = statistics.median(pipeline_ms)
    threshold_median = statistics.median(threshold_ms)
    return {
        "frame": f"{width}x{height}",
        "repeats": repeats,
        "median_ms": median_ms,
        "p90_ms": float(np.percentile(pipeline_ms, 90)),
        "threshold_median_ms": threshold_median,
        "ratio_to_threshold": median_ms / threshold_median,
        "stage_median_ms": {k: statistics.median(s[k] for s in stages) for k in stages[0]},
        "gravity": gravity,
        "cv2_threads": cv2.getNumThreads(),
        "cpu_count": os.cpu_count(),
    }
