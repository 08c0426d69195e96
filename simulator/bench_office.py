"""`lumipose bench office`: the paper's office walks (Section IV-D, Figs. 17-18).

Scene `simulator/scenes/office.json` (its pose and ID frames, its walk, its light pollution): four
coded panels on a 2.72 m ceiling over a 2.4 m x 3.6 m area, the phone face up at 1.32 m. A walker
follows the zig-zag or the converging square spiral (`simulator.trajectories`) at `speed_mps`,
with hand shake, the phone's long side along the room's Y axis. Every capture (one every
`stepped_interval_s(0.5)` = 0.499 s, paper: 0.5 s) is one pose frame (8.4 ms, a whole message:
overexposed, the code averaged away; half resolution) and `id_frames` ID frames right after it
(1/8000 s, quarter resolution; `simulator.bursts`), all rendered with every panel in view and
each panel's own LED (random phase, +-50 ppm clock).
The captures go, in order, through `server.locator.locate` with one device's sessions
(`server.tracking.devices.Devices`): ID frames first, then the pose frame, exactly as the
service sees an app's uploads. Errors are horizontal (2-D) distances of the raw fixes to the
true optical centre; an ID error is a fix whose beacon is not the panel it was measured on.
"""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Iterator
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, replace
from functools import partial
from pathlib import Path

import cv2
import numpy as np

from server.geometry import camera_matrix, rotation_from_ypr, world_to_camera
from server.ingest import LumaFrame
from server.locator import locate
from server.tracking.devices import Devices
from server.vlc.capture import ID_BURST_FRAMES, id_frame_interval_s, stepped_interval_s
from shared_schemas import Beacon, BeaconMap, FrameMeta
from simulator.bursts import burst_scenes, render_burst
from simulator.render import CameraPose
from simulator.scene import Scene, TrajectorySeries, find_scene
from simulator.trajectories import Area, hand_shake_deg, square_spiral, zigzag

PROFILE_ID = "xiaomi-mi8-front"
WALKS = ("zigzag", "spiral")
DEVICE_ID = "office-walker"


@dataclass(frozen=True)
class OfficeConfig:
    walk: str = "zigzag"
    scene: str = "office"
    speed_mps: float | None = None  # None: the scene's series
    spacing_m: float | None = None
    shake_deg: float | None = None
    inset_m: float = 0.0  # walk this far inside the scene's area
    capture_interval_s: float = stepped_interval_s(0.5)
    pose_scale: float | None = None  # of the Mi 8 front camera's 3880 x 5184; None: the scene's (0.5)
    pose_exposure_s: float | None = None  # None: the scene's (8.4 ms, a whole message: the code averages away)
    id_frames: int = ID_BURST_FRAMES
    id_interval_s: float = id_frame_interval_s()  # the app's burst: 4 frames a quarter message apart
    max_captures: int | None = None
    seed: int = 1
    panel_yaws_deg: tuple[float, ...] | None = None  # each scene panel's yaw (a surveyed room's); None: the scene's
    depth: float | None = None  # the LEDs' modulation depth (1.0: off between chips); None: the scene's


def office_scenes(config: OfficeConfig) -> tuple[Scene, Scene]:
    """(pose-frame scene, ID-frame scene) of the bundled scene (`simulator.bursts`), each panel's LED
    at a random phase."""
    scene = find_scene(config.scene)
    rng = np.random.default_rng([config.seed, 99])
    beacons = [b.model_copy(update={"vlc_phase_s": float(rng.uniform(0, 1))}) for b in scene.beacons]
    if config.depth is not None:
        beacons = [b.model_copy(update={"vlc_depth": config.depth}) for b in beacons]
    if config.panel_yaws_deg is not None:
        if len(config.panel_yaws_deg) != len(beacons):
            raise ValueError(f"panel_yaws_deg: {len(config.panel_yaws_deg)} yaws for {len(beacons)} panels")
        beacons = [b.model_copy(update={"yaw_deg": y}) for b, y in zip(beacons, config.panel_yaws_deg, strict=True)]
    updates: dict = {"beacons": beacons}
    if config.pose_exposure_s is not None:
        updates["sensor"] = scene.sensor.model_copy(update={"exposure_s": config.pose_exposure_s})
    if config.pose_scale is not None:
        updates["camera"] = scene.camera.model_copy(update={"scale": config.pose_scale})
    return burst_scenes(scene.model_copy(update=updates))


def _walk(config: OfficeConfig, scene: Scene):
    series = scene.series.path if scene.series else None
    if not isinstance(series, TrajectorySeries) or series.area_m is None:
        raise ValueError(f"scene '{scene.name}' has no walk area (series.path.area_m)")
    area = Area(*series.area_m)
    inner = Area(area.x_min_m + config.inset_m, area.y_min_m + config.inset_m,
                 area.x_max_m - config.inset_m, area.y_max_m - config.inset_m)
    make = {"zigzag": zigzag, "spiral": square_spiral}[config.walk]
    path = make(inner, config.spacing_m or series.spacing_m, config.speed_mps or series.speed_mps,
                config.capture_interval_s, series.height_m)
    return (path[: config.max_captures] if config.max_captures else path), area


def _pose_at(times: np.ndarray, positions: np.ndarray, t_s: float, seed: int, shake_deg: float) -> CameraPose:
    position = np.array([np.interp(t_s, times, positions[:, k]) for k in range(3)])
    yaw, pitch, roll = hand_shake_deg(np.array([t_s]), shake_deg, seed)[0]
    return CameraPose(position, rotation_from_ypr(yaw, pitch, roll))


def true_beacon(beacons: list[Beacon], camera, pose: CameraPose, center_px) -> int:
    """The map beacon whose centre projects nearest `center_px` for the true pose."""
    centres = np.array([b.center_m for b in beacons], float)
    in_camera = world_to_camera(centres, pose.position_m, pose.rotation_wc)
    pixels, _ = cv2.projectPoints(in_camera, np.zeros(3), np.zeros(3), camera_matrix(camera), None)
    gaps = np.linalg.norm(pixels.reshape(-1, 2) - np.asarray(center_px), axis=1)
    return beacons[int(np.argmin(gaps))].id


def _luma_frame(scene: Scene, rendered: tuple[np.ndarray, FrameMeta]) -> LumaFrame:
    pixels, meta = rendered
    return LumaFrame(pixels, FrameMeta.model_validate(meta.model_dump(by_alias=True)), scene.camera.intrinsics())


@dataclass(frozen=True)
class Capture:
    """One capture of a walk: the true pose, the pose frame and the ID frames taken after it."""

    t_s: float
    pose: CameraPose
    pose_frame: LumaFrame
    id_frames: tuple[LumaFrame, ...]


def walk_captures(config: OfficeConfig) -> Iterator[Capture]:
    """The walk's captures in order, rendered one at a time (deterministic for `config.seed`)."""
    pose_scene, id_scene = office_scenes(config)
    rng = np.random.default_rng([config.seed, WALKS.index(config.walk)])
    path, _ = _walk(config, pose_scene)
    shake = config.shake_deg if config.shake_deg is not None else pose_scene.series.rotation.shake_deg
    times = np.array([p.t_s for p in path])
    positions = np.array([p.position_m for p in path])
    shake_seed = config.seed * 7919 + WALKS.index(config.walk)

    def pose_at(t: float) -> CameraPose:
        return _pose_at(times, positions, t, shake_seed, shake)

    for t_s in map(float, times):
        pose_frame, *id_frames = render_burst((pose_scene, id_scene), t_s, pose_at, rng, config.id_frames,
                                              config.id_interval_s)
        yield Capture(t_s, pose_at(t_s), _luma_frame(pose_scene, pose_frame),
                      tuple(_luma_frame(id_scene, frame) for frame in id_frames))


def run_walk(config: OfficeConfig, beacon_map: BeaconMap | None = None) -> dict:
    """Render and process one walk, capture by capture; per-capture records and a summary. The frames
    are located in `beacon_map` (a surveyed one, `lumipose bench survey`), else in the scene's true map;
    errors are always against the true poses."""
    pose_scene, _ = office_scenes(config)
    true_map = pose_scene.beacon_map()
    beacon_map = beacon_map or true_map
    beacons = list(true_map.beacons)
    pose_camera = pose_scene.camera.intrinsics()
    devices = Devices()
    records = []
    total = len(_walk(config, pose_scene)[0])
    for k, capture in enumerate(walk_captures(config)):
        for id_frame in capture.id_frames:
            locate(id_frame, beacon_map, device_id=DEVICE_ID, devices=devices)
        result = locate(capture.pose_frame, beacon_map, device_id=DEVICE_ID, devices=devices)
        pose = capture.pose
        nearest = min(beacons, key=lambda b: math.hypot(b.center_m[0] - pose.position_m[0],
                                                        b.center_m[1] - pose.position_m[1])).id
        record = {"t_s": capture.t_s, "truth_m": pose.position_m.tolist(), "ok": result.ok,
                  "reason": None if result.ok else result.reason.value, "in_view": result.beacons_in_view,
                  "nearest_beacon": nearest}
        if result.ok:
            record.update({
                "fix_m": result.position_m, "beacon_id": result.beacon_id,
                "source": result.beacon_id_source.value,
                "true_beacon": true_beacon(beacons, pose_camera, pose, result.center_px),
                "error_mm": 1000.0 * math.hypot(result.position_m[0] - pose.position_m[0],
                                                result.position_m[1] - pose.position_m[1]),
                "vlc_confidence": None if result.vlc is None else result.vlc.confidence,
            })
        if result.vlc is not None:  # what the stripes read, used or not
            record.update({"vlc_id": result.vlc.beacon_id, "vlc_confident": result.vlc.confident})
        if result.track is not None:
            record["filtered_m"] = result.track.filtered_position_m
            record["outlier"] = result.track.outlier
        records.append(record)
        _progress(k + 1, total, config.walk)
    stats = devices.stats(DEVICE_ID)
    return {"config": asdict(config), "summary": summarize_walk(records), "records": records,
            "stats": asdict(stats) if stats is not None else {}}


def _progress(done: int, total: int, label: str) -> None:
    if done == total or done % max(1, total // 10) == 0:
        print(f"{label}: {done}/{total}", file=sys.stderr, flush=True)


def _error_summary(errors: list[float]) -> dict:
    if not errors:
        return {"mean_mm": None, "p95_mm": None, "max_mm": None}
    e = np.array(errors)
    return {"mean_mm": float(e.mean()), "p95_mm": float(np.percentile(e, 95)), "max_mm": float(e.max())}


def summarize_walk(records: list[dict]) -> dict:
    ok = [r for r in records if r["ok"]]
    # transitions: captures within one capture of a change of the nearest beacon
    nearest = [r["nearest_beacon"] for r in records]
    near_change = {i for i in range(len(records)) for j in (i - 1, i + 1)
                   if 0 <= j < len(records) and nearest[j] != nearest[i]}
    transition = [r for i, r in enumerate(records) if i in near_change]
    filtered = [1000.0 * math.hypot(r["filtered_m"][0] - r["truth_m"][0], r["filtered_m"][1] - r["truth_m"][1])
                for r in ok if "filtered_m" in r]
    reasons: dict[str, int] = {}
    for r in records:
        if not r["ok"]:
            reasons[r["reason"]] = reasons.get(r["reason"], 0) + 1
    return {
        "captures": len(records),
        "coverage_pct": 100.0 * len(ok) / max(1, len(records)),
        "fixes": _error_summary([r["error_mm"] for r in ok]),
        "filtered": _error_summary(filtered),
        "id_errors": sum(r["beacon_id"] != r["true_beacon"] for r in ok),
        "ids_by_vlc": sum(r["source"] == "vlc" for r in ok),
        "ids_carried": sum(r["source"] == "track" for r in ok),
        # the result's VLC reading, confident, against the panel the fix was measured on
        "vlc_confident_right": sum(bool(r.get("vlc_confident")) and r["vlc_id"] == r["true_beacon"] for r in ok),
        "vlc_confident_wrong": sum(bool(r.get("vlc_confident")) and r["vlc_id"] != r["true_beacon"] for r in ok),
        "outliers": sum(bool(r.get("outlier")) for r in ok),
        "transition_captures": len(transition),
        "transition_coverage_pct": 100.0 * sum(r["ok"] for r in transition) / max(1, len(transition)),
        "transition_fixes": _error_summary([r["error_mm"] for r in transition if r["ok"]]),
        "refusals": reasons,
    }


def run_office(config: OfficeConfig, walks: tuple[str, ...] = WALKS, workers: int | None = None,
               beacon_map: BeaconMap | None = None) -> list[dict]:
    workers = min(len(walks), workers or os.cpu_count() or 1)
    configs = [replace(config, walk=w) for w in walks]
    walk = partial(run_walk, beacon_map=beacon_map)
    if workers == 1:
        return [walk(c) for c in configs]
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return list(pool.map(walk, configs))


def plot_walk(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    pose_scene, _ = office_scenes(OfficeConfig(**report["config"]))
    beacon_map = pose_scene.beacon_map()
    _, area = _walk(OfficeConfig(**report["config"]), pose_scene)
    colours = dict(zip(sorted(b.id for b in beacon_map.beacons), ["tab:blue", "tab:orange", "tab:green", "tab:red"]))
    records = report["records"]
    fig, ax = plt.subplots(figsize=(5.4, 7.6))
    for b in beacon_map.beacons:  # each beacon's quarter of the area, softly coloured
        qx = area.x_min_m if b.center_m[0] < 0 else 0.0
        qy = area.y_min_m if b.center_m[1] < 0 else 0.0
        ax.add_patch(plt.Rectangle((qx, qy), area.x_max_m, area.y_max_m, color=colours[b.id], alpha=0.08))
        s = b.size_m
        ax.add_patch(plt.Rectangle((b.center_m[0] - s / 2, b.center_m[1] - s / 2), s, s, color=colours[b.id]))
        ax.annotate(f"ID {b.id}", (b.center_m[0], b.center_m[1] + 0.12), ha="center", fontsize=8)
    for beacon_id, colour in colours.items():
        fixes = np.array([r["fix_m"] for r in records if r["ok"] and r["beacon_id"] == beacon_id])
        if len(fixes):
            ax.plot(fixes[:, 0], fixes[:, 1], ".", color=colour, ms=4, label=f"fixes from ID {beacon_id}")
    filtered = np.array([r["filtered_m"] for r in records if "filtered_m" in r])
    if len(filtered):
        ax.plot(filtered[:, 0], filtered[:, 1], "-", color="tab:purple", lw=2.6, alpha=0.45, label="filtered track",
                zorder=3)  # wide and pale under the truth: both stay visible where they coincide
    # the truth last and dashed in black, a colour no beacon has, so the track cannot hide it
    truth = np.array([r["truth_m"] for r in records])
    ax.plot(truth[:, 0], truth[:, 1], "--", color="black", lw=0.9, label="true path", zorder=4)
    missed = np.array([r["truth_m"] for r in records if not r["ok"]])
    if len(missed):
        ax.plot(missed[:, 0], missed[:, 1], "x", color="black", ms=6, mew=1.5, label="no fix", zorder=5)
    s = report["summary"]
    ax.set_title(f"{report['config']['walk']}: mean {s['fixes']['mean_mm']:.1f} mm, coverage {s['coverage_pct']:.1f} %, "
                 f"ID errors {s['id_errors']}", fontsize=9)
    ax.set_xlim(area.x_min_m - 0.1, area.x_max_m + 0.1)
    ax.set_ylim(area.y_min_m - 0.1, area.y_max_m + 0.1)
    ax.set_aspect("equal")
    ax.set_xlabel("X (m)")
    ax.set_ylabel("Y (m)")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08), ncol=3, frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
