"""`lumipose bench vlc`: ID success rate against distance (the paper's Fig. 16), and exposure.

Each trial: a random beacon ID (0-255), a panel of `shape` (`square`: a rounded square of side
`side_m`; `rect`: a rounded rectangle `side_m` long and `aspect` x `side_m` wide, e.g. 1200 x
300 mm; `circle`: a round downlight of diameter `side_m`), judged by the blob rules of a map of
that panel (`CandidateRules.for_beacons`), a random phone pose under the panel (anywhere the
whole panel stays in the frame, tilt up to `max_tilt_deg`, any yaw: a rectangle's long side
lies at any angle to the sensor's rows), an LED with a random
message phase and a crystal error of up to +-50 ppm, and a burst of ID frames (quarter
resolution of the Mi 8 front camera, 1/8000 s, rolling_shutter_skew_s = 30 ms, frames
`stepped_interval_s(1/30)` apart, hand jitter between frames). Frames are rendered by
`simulator.render.render_frame` with `simulator.led.row_gains`, then decoded by the server's
code path (`server.vlc.reader` + `IdEvidence`) among all 256 IDs:
- single frame: the decision after the first frame;
- combined: frames added one by one until the decision is confident, at most `max_frames`.
Success = a confident, correct ID; a confident wrong ID is counted apart (it must be 0).

With `map_ids` = K > 0 the decoder is given a map of K IDs, as a room's or a session's is
(`IdEvidence.for_map`): in a share `foreign_share` of the trials the panel is not of the map
and the map holds an ID one bit from the panel's (the hardest foreign panel: its code differs
from a map code in 2 to 4 chips), otherwise the panel's ID and K - 1 random others. Then
"read" = a confident, correct ID among the map panels' trials, "named wrong" = a confident map
ID that is not the panel's (any trial), "foreign confident" = a confident ID outside the map.

`depth`: the LED's modulation depth (a 0 chip is 1 - depth of a 1 chip; 0.7 by default, 1.0 an
LED keyed fully off between chips, as OOK or full-depth PWM drivers do). "captures" = the ID frames
used counted in the app's bursts of `ID_BURST_FRAMES` (4) per capture.
"""

from __future__ import annotations

import math
import os
import sys
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass

import numpy as np

from server.camera import intrinsics_from_profile
from server.fov import fov_grid
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.vision.beacons import CandidateRules
from server.vlc.capture import ID_BURST_FRAMES, ID_EXPOSURE_S, stepped_interval_s
from server.vlc.codec import DEFAULT_DEPTH, LedWaveform
from server.vlc.decoder import IdEvidence
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, FrameKind, device_profiles
from simulator.fixtures import fixture_meta
from simulator.led import row_gains
from simulator.render import CameraPose, SensorModel, beacon_outline_px, render_frame

PROFILE_ID = "xiaomi-mi8-front"
SHAPES = ("square", "rect", "circle")


@dataclass(frozen=True)
class VlcConfig:
    distance_m: float = 1.0
    trials: int = 100
    max_frames: int = 12
    side_m: float = 0.174  # a square's side, a rectangle's long side, a circle's diameter
    corner_radius_m: float = 0.02  # squares and rectangles
    shape: str = "square"  # one of SHAPES
    aspect: float = 0.25  # a rectangle's short side over its long side
    exposure_s: float = ID_EXPOSURE_S
    skew_s: float = 0.03
    scale: float = 0.25
    frame_interval_s: float = stepped_interval_s(1.0 / 30.0)
    max_tilt_deg: float = 10.0
    clock_error_ppm: float = 50.0
    plateau_dn: float = 200.0  # LED high level in an ID frame (ISO raised for the short exposure)
    electrons_per_dn: float = 4.0  # high gain: fewer electrons per DN, more shot noise
    read_noise_dn: float = 2.0
    depth: float = DEFAULT_DEPTH  # modulation depth: the LED low level is 1 - depth of its high (1.0: off)
    seed: int = 1
    map_ids: int = 0  # 0: no map, all 256 IDs as candidates; K: a map of K IDs
    foreign_share: float = 0.5  # with a map: trials whose panel is not of the map


def bench_beacon(config: VlcConfig, beacon_id: int) -> Beacon:
    """The panel of `config`'s shape, `config.distance_m` above the origin."""
    centre = [0.0, 0.0, config.distance_m]
    if config.shape == "circle":
        return Beacon(id=beacon_id, center_m=centre, shape="circle", diameter_m=config.side_m)
    if config.shape == "rect":
        short = config.side_m * config.aspect
        radius = min(config.corner_radius_m, 0.4 * short)
        return Beacon(id=beacon_id, center_m=centre, width_m=config.side_m, height_m=short, corner_radius_m=radius)
    if config.shape == "square":
        return Beacon(id=beacon_id, center_m=centre, side_m=config.side_m, corner_radius_m=config.corner_radius_m)
    raise ValueError(f"shape must be one of {SHAPES}, got {config.shape!r}")


def id_sensor(config: VlcConfig, rng: np.random.Generator) -> SensorModel:
    return SensorModel(background_dn=3.0, plateau_dn=config.plateau_dn, psf_sigma_px=rng.uniform(0.8, 1.5),
                       electrons_per_dn=config.electrons_per_dn, read_noise_dn=config.read_noise_dn)


def _draw_pose(config: VlcConfig, beacon: Beacon, camera, width: int, height: int, rng) -> CameraPose:
    profile = device_profiles()[PROFILE_ID]
    extent = fov_grid(profile, config.distance_m, 0.05, config.side_m).beacon_adjusted_m
    for _ in range(1000):
        xy = rng.uniform(-0.5, 0.5, 2) * extent
        tilt, azimuth = rng.uniform(0.0, config.max_tilt_deg), rng.uniform(0.0, 2 * math.pi)
        rotation = rotation_from_ypr(rng.uniform(-180, 180), tilt * math.cos(azimuth), tilt * math.sin(azimuth))
        pose = CameraPose(np.array([xy[0], xy[1], 0.0]), rotation)
        outline = beacon_outline_px(beacon, camera, pose)
        if (outline.min(axis=0) > 4).all() and (outline.max(axis=0) < [width - 4, height - 4]).all():
            return pose
    raise RuntimeError(f"no pose keeps a {config.side_m} m panel in view at {config.distance_m} m")


def _jitter(pose: CameraPose, rng) -> CameraPose:
    """A hand-held phone between two ID frames: a few millimetres and a few tenths of a degree."""
    turn = rotation_from_ypr(*rng.normal(0.0, 0.2, 3))
    return CameraPose(pose.position_m + rng.normal(0.0, 0.002, 3) * [1, 1, 0], pose.rotation_wc @ turn)


def trial_map(config: VlcConfig, index: int, beacon_id: int) -> tuple[tuple[int, ...], bool]:
    """The map IDs of trial `index` (empty: no map) and whether the panel is foreign to it (its own stream of
    random numbers: the panel, pose and noise are the same with a map as without)."""
    if config.map_ids <= 0:
        return (), False
    rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000), 7])
    foreign = bool(rng.random() < config.foreign_share)
    others = [i for i in range(256) if i != beacon_id]
    if foreign:
        near = beacon_id ^ (1 << int(rng.integers(0, 8)))
        rest = rng.choice([i for i in others if i != near], config.map_ids - 1, replace=False)
        return tuple(sorted([near, *map(int, rest)])), True
    rest = rng.choice(others, config.map_ids - 1, replace=False)
    return tuple(sorted([beacon_id, *map(int, rest)])), False


def _trial(args: tuple[VlcConfig, int]) -> dict:
    config, index = args
    rng = np.random.default_rng([config.seed, index, int(config.distance_m * 1000)])
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * config.scale), round(profile.height * config.scale)
    camera = intrinsics_from_profile(profile, width, height)
    beacon_id = int(rng.integers(0, 256))
    beacon = bench_beacon(config, beacon_id)
    candidates = CandidateRules().for_beacons([beacon])
    wave = LedWaveform.for_beacon(beacon_id, depth=config.depth, phase_s=rng.uniform(0, 1),
                                  clock_error_ppm=rng.uniform(-1, 1) * config.clock_error_ppm)
    pose = _draw_pose(config, beacon, camera, width, height, rng)
    row_time = config.skew_s / (height - 1)
    map_ids, foreign = trial_map(config, index, beacon_id)
    evidence = IdEvidence(map_ids=map_ids)
    single = None
    start_s = float(rng.uniform(0, 10))
    for k in range(config.max_frames):
        t_s = start_s + k * config.frame_interval_s
        gains = row_gains(wave, height, row_time, config.exposure_s, t_s)
        pixels = render_frame(beacon, camera, pose, width, height, id_sensor(config, rng), rng, row_gain=gains)
        meta = fixture_meta(camera, width, height, pose).model_copy(update={
            "exposure_s": config.exposure_s, "rolling_shutter_skew_s": config.skew_s,
            "timestamp_ns": int(round(t_s * 1e9)), "frame_kind": FrameKind.id})
        reading = read_id_frame(LumaFrame(pixels, meta, camera), candidates)
        panels = [p for p in reading.panels if p.observation is not None]
        if panels:
            evidence.add(max(panels, key=lambda p: p.blob.area_px).observation)
        decision = evidence.decide()
        if k == 0:
            single = decision
        if decision.confident:
            break
        pose = _jitter(pose, rng)
    return {
        "id": beacon_id,
        "map": list(map_ids),
        "foreign": foreign,
        "single": [single.beacon_id, single.confident, single.chips_seen],
        "combined": [decision.beacon_id, decision.confident, k + 1, decision.chips_seen],
    }


def _rates(rows: list[list], truth: list[int]) -> dict:
    confident = [r[1] for r in rows]
    right = [c and r[0] == t for r, c, t in zip(rows, confident, truth, strict=True)]
    wrong = [c and r[0] != t for r, c, t in zip(rows, confident, truth, strict=True)]
    return {"success_pct": 100.0 * np.mean(right), "confident_wrong": int(np.sum(wrong)),
            "no_decision": int(len(rows) - np.sum(confident))}


def _map_rates(trials: list[dict], key: str) -> dict:
    """Read rate among the map panels' trials, wrong namings and confident foreign IDs among all."""
    own = [t for t in trials if not t["foreign"]]
    read = [t[key][1] and t[key][0] == t["id"] for t in own]
    named_wrong = [t[key][1] and t[key][0] in t["map"] and t[key][0] != t["id"] for t in trials]
    foreign = [t[key][1] and t[key][0] not in t["map"] for t in trials]
    return {"map_trials": len(own), "foreign_trials": len(trials) - len(own),
            "read_pct": 100.0 * float(np.mean(read)) if read else math.nan,
            "named_wrong": int(np.sum(named_wrong)), "foreign_confident": int(np.sum(foreign))}


def run_vlc(config: VlcConfig, workers: int | None = None) -> dict:
    workers = workers or os.cpu_count() or 1
    with ProcessPoolExecutor(max_workers=workers) as pool:
        trials = list(pool.map(_trial, [(config, i) for i in range(config.trials)], chunksize=2))
    truth = [t["id"] for t in trials]
    single = _rates([t["single"] for t in trials], truth)
    single["chips_per_frame"] = float(np.mean([t["single"][2] for t in trials]))
    combined = _rates([t["combined"] for t in trials], truth)
    frames = [t["combined"][2] for t in trials if t["combined"][1]]
    combined["mean_frames"] = float(np.mean(frames)) if frames else math.nan
    combined["mean_captures"] = float(np.mean(np.ceil(np.array(frames) / ID_BURST_FRAMES))) if frames else math.nan
    combined["max_frames_used"] = int(max(frames)) if frames else 0
    if config.map_ids > 0:
        single["map"], combined["map"] = _map_rates(trials, "single"), _map_rates(trials, "combined")
    print(f"vlc, {config.shape} {config.side_m} m, at {config.distance_m:.2f} m, exposure {config.exposure_s:.2g} s, "
          f"depth {config.depth:g}: "
          f"single {single['success_pct']:.0f} %, combined {combined['success_pct']:.0f} %", file=sys.stderr)
    extent = bench_beacon(config, 0).extent_m
    return {"distance_m": config.distance_m, "exposure_s": config.exposure_s, "depth": config.depth, "side_m": config.side_m,
            "shape": config.shape, "extent_m": list(extent), "trials": config.trials, "max_frames": config.max_frames,
            "map_ids": config.map_ids, "foreign_share": config.foreign_share if config.map_ids else None,
            "single": single, "combined": combined, "trials_run": trials}  # per trial, for `bench results`


def panel_name(report: dict) -> str:
    """"0.174 m panel" (a square, as the figures before shapes said), "1200 x 300 mm rect", "0.2 m circle"."""
    shape = report.get("shape", "square")
    if shape == "rect":
        width, height = report["extent_m"]
        return f"{width * 1000:.0f} x {height * 1000:.0f} mm rect"
    return f"{report['side_m']} m {'circle' if shape == 'circle' else 'panel'}"


def plot_vlc(reports: list[dict], path, title: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    def key(r: dict) -> tuple:
        return r.get("shape", "square"), r["side_m"], r.get("depth", DEFAULT_DEPTH)

    panels = sorted({key(r) for r in reports})
    depths = {depth for *_, depth in panels}
    for panel in panels:
        rows = sorted((r for r in reports if key(r) == panel), key=lambda r: r["distance_m"])
        d = [r["distance_m"] for r in rows]
        name = panel_name(rows[0]) + (f", depth {panel[2]:g}" if len(depths) > 1 else "")
        ax.plot(d, [r["single"]["success_pct"] for r in rows], "o--", label=f"single frame, {name}")
        ax.plot(d, [r["combined"]["success_pct"] for r in rows], "s-",
                label=f"combined (<= {rows[0]['max_frames']} frames), {name}")
    ax.plot([1.0, 1.3, 3.0], [100, 100, 0], "kx", markersize=9, label="paper Fig. 16 (stated points)")
    ax.set_xlabel("distance camera - panel (m)")
    ax.set_ylabel("confident correct ID (%)")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.set_title(title)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)  # off the data
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


@dataclass(frozen=True)
class CutConfig:
    """`lumipose bench vlc --cut`: one ID frame of a panel cut by the frame border, read by the room path.

    The panel (a 600 x 600 mm square by default) is cut by the frame's bottom border (`edge =
    "bottom"`: only `share` of its rows in view) or its right border (`"side"`: `share` of its
    columns, every row) by placing the camera; the frame goes through `server.rooms.read_room`
    with a two-beacon map (the second panel far out of view), as a phone without a session would
    send it. Per trial: named (right, wrong or not) and, when named, the 2D error of its fix.
    """

    share: float = 0.7
    edge: str = "bottom"  # or "side"
    distance_m: float = 1.2
    side_m: float = 0.6
    corner_radius_m: float = 0.01
    trials: int = 20
    max_yaw_deg: float = 30.0  # a square's corner order needs the phone's yaw within 45 degrees of the panel's
    max_tilt_deg: float = 5.0
    depth: float = DEFAULT_DEPTH  # the LED's modulation depth (1.0: off between chips)
    seed: int = 1


def _cut_pose(config: CutConfig, beacon: Beacon, camera, width: int, height: int, rng) -> CameraPose | None:
    """A camera pose whose frame shows `config.share` of the panel's rows (bottom) or columns (side)."""
    tilt, azimuth = rng.uniform(0.0, config.max_tilt_deg), rng.uniform(0.0, 2 * math.pi)
    yaw = rng.uniform(-1, 1) * config.max_yaw_deg
    rotation = rotation_from_ypr(yaw, tilt * math.cos(azimuth), tilt * math.sin(azimuth))
    axis, limit = (1, height) if config.edge == "bottom" else (0, width)
    # the camera moves along its image axis `axis`, levelled; the panel moves the other way in the image
    direction = rotation[:, axis] * [1.0, 1.0, 0.0]
    direction /= np.linalg.norm(direction)
    across = np.cross([0.0, 0.0, 1.0], direction) * rng.uniform(-0.05, 0.05)

    def pose_at(offset: float) -> CameraPose:
        return CameraPose(offset * direction + across, rotation)

    def shown(offset: float) -> float:
        outline = beacon_outline_px(beacon, camera, pose_at(offset))
        low, high = outline[:, axis].min(), outline[:, axis].max()
        return float(np.clip((limit - low) / (high - low), 0.0, 1.0))

    more, less = 2.0, -2.0  # offsets showing more and less of the panel than wanted
    if shown(more) < shown(less):
        more, less = less, more
    if not shown(more) > config.share > shown(less):
        return None
    for _ in range(40):
        middle = (more + less) / 2
        if shown(middle) > config.share:
            more = middle
        else:
            less = middle
    return pose_at((more + less) / 2)


def _cut_trial(args: tuple[CutConfig, int]) -> dict:
    from server.rooms import read_room
    from shared_schemas import BeaconMap

    config, index = args
    rng = np.random.default_rng([config.seed, index, int(config.share * 1000), config.edge == "side"])
    profile = device_profiles()[PROFILE_ID]
    width, height = round(profile.width * 0.25), round(profile.height * 0.25)
    camera = intrinsics_from_profile(profile, width, height)
    beacon_id = int(rng.integers(0, 255))
    beacon = Beacon(id=beacon_id, center_m=[0.0, 0.0, config.distance_m], side_m=config.side_m,
                    corner_radius_m=config.corner_radius_m)
    far = Beacon(id=beacon_id + 1, center_m=[30.0, 0.0, config.distance_m], side_m=config.side_m,
                 corner_radius_m=config.corner_radius_m)
    beacon_map = BeaconMap(name="cut", beacons=[beacon, far])
    pose = _cut_pose(config, beacon, camera, width, height, rng)
    if pose is None:
        raise RuntimeError(f"no pose shows {config.share} of the panel at its {config.edge}")
    wave = LedWaveform.for_beacon(beacon_id, depth=config.depth, phase_s=rng.uniform(0, 1),
                                  clock_error_ppm=rng.uniform(-50, 50))
    t_s = float(rng.uniform(0, 10))
    skew_s, exposure_s = 0.03, ID_EXPOSURE_S
    gains = row_gains(wave, height, skew_s / (height - 1), exposure_s, t_s)
    sensor = SensorModel(background_dn=3.0, plateau_dn=200.0, psf_sigma_px=rng.uniform(0.8, 1.5), electrons_per_dn=4.0,
                         read_noise_dn=2.0)
    pixels = render_frame(beacon, camera, pose, width, height, sensor, rng, row_gain=gains)
    gravity = (pose.rotation_wc.T @ [0, 0, -1.0]).tolist()
    meta = fixture_meta(camera, width, height, pose, gravity_camera=gravity).model_copy(update={
        "exposure_s": exposure_s, "rolling_shutter_skew_s": skew_s, "timestamp_ns": int(round(t_s * 1e9)),
        "frame_kind": FrameKind.id})
    room = read_room(LumaFrame(pixels, meta, camera), beacon_map)
    cut = [p for p in room.panels if p.blob.cut_off]
    record: dict = {"id": beacon_id, "found": bool(cut), "rows": None, "chips": None, "named": None,
                    "error_mm": None, "refusal": None}
    if cut:
        panel = max(cut, key=lambda p: p.blob.area_px)
        record["rows"] = panel.blob.bounding_box[3]
        record["chips"] = None if panel.vlc is None else panel.vlc.chips_seen
        record["named"] = None if panel.beacon is None else panel.beacon.id
        if panel.fix is not None and hasattr(panel.fix, "position_m"):
            record["error_mm"] = 1000 * float(np.linalg.norm(panel.fix.position_m[:2] - pose.position_m[:2]))
            record["position_m"] = [float(v) for v in panel.fix.position_m]
        elif panel.fix is not None:
            record["refusal"] = panel.fix.reason.value
    return record


def run_cut(config: CutConfig, workers: int | None = None) -> dict:
    workers = workers or os.cpu_count() or 1
    with ProcessPoolExecutor(max_workers=workers) as pool:
        records = list(pool.map(_cut_trial, [(config, i) for i in range(config.trials)], chunksize=2))
    named = [r for r in records if r["named"] is not None]
    right = [r for r in named if r["named"] == r["id"]]
    errors = [r["error_mm"] for r in right if r["error_mm"] is not None]
    chips = [r["chips"] for r in records if r["chips"] is not None]
    rows = [r["rows"] for r in records if r["rows"] is not None]
    refusals: dict[str, int] = {}
    for r in right:
        if r["refusal"]:
            refusals[r["refusal"]] = refusals.get(r["refusal"], 0) + 1
    summary = {
        "edge": config.edge, "share": config.share, "distance_m": config.distance_m, "depth": config.depth,
        "side_m": config.side_m,
        "trials": config.trials, "found": sum(r["found"] for r in records),
        "rows": float(np.mean(rows)) if rows else math.nan,
        "chips": float(np.mean(chips)) if chips else math.nan,
        "named_pct": 100.0 * len(right) / config.trials, "named_wrong": len(named) - len(right),
        "located": len(errors), "mean_mm": float(np.mean(errors)) if errors else math.nan,
        "max_mm": float(np.max(errors)) if errors else math.nan, "refusals": refusals,
        "trials_run": records,  # per trial, for `bench results`
    }
    print(f"vlc cut at the {config.edge}, {config.share:.2f} in view: named {summary['named_pct']:.0f} %, "
          f"located {len(errors)}", file=sys.stderr)
    return summary


def plot_cut(reports: list[dict], path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for edge, label in (("bottom", "cut by the bottom border (rows lost)"), ("side", "cut by a side (rows kept)")):
        rows = sorted((r for r in reports if r["edge"] == edge), key=lambda r: r["share"])
        if rows:
            ax.plot([100 * r["share"] for r in rows], [r["named_pct"] for r in rows], "o-", label=label)
    ax.set_xlabel("share of the panel's rows (bottom) or columns (side) in view (%)")
    ax.set_ylabel("named by VLC from one ID frame (%)")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    side = reports[0]["side_m"] if reports else 0.6
    distance = reports[0]["distance_m"] if reports else 1.2
    ax.set_title(f"a {side} m panel cut by the frame border, {distance} m, one 1/8000 s frame")
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
