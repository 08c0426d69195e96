"""`lumipose bench speed`: every path of issue 30's table as a ratio to one reference pass.

The reference pass is `cv2.threshold(full 3880 x 5184 frame, 128, 255, THRESH_BINARY, dst=preallocated)`
on one OpenCV thread (set around it only: OpenCV's two threads and a fresh 20 MB output move the ratio
by 10-30 %), timed just before each measured call in the same loop, so that both see the same machine.
A path's ratio is the median over its frames and rounds of (call time / reference time); each round's
median is reported too, to show how much the machine moved it (2 shared cores: timings are noisy,
ratios in one run less so).

The paths and their frames, each another bench's own frames (no frame maker of their own here):
- `square`, `square-quarter`: the accuracy bench's frames (`accuracy_frame`), full and quarter resolution,
  `frames` per distance (1, 2, 3 m), located as `bench speed` always did (default options);
- `cut`: `bench partial`'s frames (`partial_frame`: 20-95 % of the panel in view), quarter and full;
- `rectangle`, `circle`: `bench shapes`' 1200 x 300 mm rectangle and 0.2 m circle (`shape_frame`), 1.4 m
  above the camera, quarter and full;
- `id-frame`: the ID frames of the Android bench's captures at 1 m (`simulate --bursts`: full resolution,
  1/8000 s), each as the device session reads it (`server.locator.locate` with a device and a map of two
  panels: the stripes kept for the pose frame), the whole frame and the window the app sends;
- `first-capture`: a device's first capture at 1 m (its 4 ID windows, then its pose window, as the app
  uploads a burst), through `locate` with a fresh device store, as an upload reaches it;
- `service-full`, `service-window`: `bench load`'s frames (`service_frame`: the 20 MB raw frame and its
  window) posted to a real `lumipose serve` on loopback; the time of the request minus the pipeline's own
  `timing_ms["total"]` from the result: what the service costs around the pipeline.
"""

from __future__ import annotations

import json
import math
import os
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from server.ingest import LumaFrame, decode_frame
from server.locator import locate
from server.options import LocateOptions
from server.tracking.devices import Devices
from shared_schemas import BeaconMap, FrameKind, FrameMeta, LocateResult

QUARTER = 0.25  # the streaming resolution (970 x 1296)
# bench shapes' circle frames with the sigma cap lifted: the same fit, but a fix at the end (with the map's
# 10 mm cap most of them end in pose_uncertain, which would hide a decision that changed)
CIRCLE = "circle-200-uncapped"
REFERENCE_THRESHOLD_DN = 128


@dataclass(frozen=True)
class Target:
    """A row of the issue's table: the ratio it must reach, and what it measured before the work."""

    label: str
    ratio: float
    issue_before: str  # the issue's own figure (wall, a quiet machine), beside the measured ones


# (path, variant) -> its row of issue 30's table, in the table's order
TARGETS: dict[tuple[str, str], Target] = {
    ("square", "full"): Target("whole square, full resolution", 2.0, "4.4-5.4x"),
    ("square-quarter", "quarter"): Target("whole square, quarter resolution", 1.0, "3.9x"),
    ("cut", "quarter"): Target("cut panel, quarter", 8.0, "55x"),
    ("cut", "full"): Target("cut panel, full", 8.0, "80x"),
    ("rectangle", "quarter"): Target("1200 x 300 rectangle, quarter", 10.0, "245x"),
    ("rectangle", "full"): Target("1200 x 300 rectangle, full", 10.0, "282x"),
    ("circle", "quarter"): Target("0.2 m circle, quarter", 8.0, "86x"),
    ("circle", "full"): Target("0.2 m circle, full", 8.0, "157x"),
    ("id-frame", "whole"): Target("ID frame at 1 m, whole frame", 2.0, "7-8x"),
    ("id-frame", "window"): Target("ID frame at 1 m, window", 2.0, "4.8x"),
    ("first-capture", "window"): Target("a device's first capture at 1 m (4 ID + pose)", 30.0, "233-253x"),
    ("service-full", "raw"): Target("service, full 20 MB upload: outside the pipeline", 6.0, "18-25"),
    ("service-window", "raw"): Target("service, window upload: outside the pipeline", 1.5, "3-4"),
}
PATHS = tuple(dict.fromkeys(path for path, _ in TARGETS))


@dataclass(frozen=True)
class SpeedConfig:
    paths: tuple[str, ...] = PATHS
    frames: int = 3  # per distance (square, cut); per path at its one distance otherwise (x the distances' count)
    rounds: int = 5  # passes over all the frames
    repeats: int = 1  # timed calls of each frame per round
    distances_m: tuple[float, ...] = (1.0, 2.0, 3.0)  # square and cut; the ID paths take the first
    gravity: bool = True  # the frames carry the phone's gravity vector (the MAP pose fit); False: none
    seed: int = 1


@dataclass(frozen=True)
class Timed:
    """One measured call: the seconds that count, and the decision it took (for the report's refusals)."""

    seconds: float  # wall time
    ok: bool
    cpu_s: float | None = None  # this process's CPU time over the call (all its threads); None for the service
    request_s: float | None = None  # the service paths: the whole request (seconds = outside the pipeline)


@dataclass(frozen=True)
class Case:
    """One frame (or capture) of a path: the call to time and the full-size frame its reference pass reads."""

    call: Callable[[], Timed]
    reference: np.ndarray


def _clock() -> tuple[float, float]:
    return time.perf_counter(), time.process_time()


def _timed(start: tuple[float, float], ok: bool) -> Timed:
    """The wall and CPU time since `start` (`_clock()`)."""
    return Timed(time.perf_counter() - start[0], ok, time.process_time() - start[1])


def reference_pass_s(pixels: np.ndarray, out: np.ndarray) -> Timed:
    """One `cv2.threshold` pass over `pixels` into the preallocated `out`, on one OpenCV thread."""
    threads = cv2.getNumThreads()
    cv2.setNumThreads(1)
    try:
        start = _clock()
        cv2.threshold(pixels, REFERENCE_THRESHOLD_DN, 255, cv2.THRESH_BINARY, dst=out)
        return _timed(start, True)
    finally:
        cv2.setNumThreads(threads)


def _timed_locate(frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions = LocateOptions()) -> Timed:
    start = _clock()
    result = locate(frame, beacon_map, options)
    return _timed(start, result.ok)


def _without_gravity(frame: LumaFrame) -> LumaFrame:
    return replace(frame, meta=frame.meta.model_copy(update={"gravity_camera": None}))


def _locate_case(frame: LumaFrame, beacon_map: BeaconMap, options: LocateOptions, reference: np.ndarray,
                 gravity: bool) -> Case:
    frame = frame if gravity else _without_gravity(frame)
    return Case(lambda: _timed_locate(frame, beacon_map, options), reference)


def _full_size(pixels: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    return pixels if pixels.shape == fallback.shape else fallback


def square_cases(config: SpeedConfig, scale: float, reference: np.ndarray) -> list[Case]:
    from simulator.benchmarks import AccuracyConfig, accuracy_frame

    cases = []
    for distance_m in config.distances_m:
        for index in range(config.frames):
            frame, beacon_map, _ = accuracy_frame(AccuracyConfig(distance_m=distance_m, seed=config.seed,
                                                                 scale=scale), index)
            cases.append(_locate_case(frame, beacon_map, LocateOptions(), _full_size(frame.pixels, reference),
                                      config.gravity))
    return cases


def cut_cases(config: SpeedConfig, scale: float, reference: np.ndarray) -> list[Case]:
    from simulator.bench_partial import PartialConfig, partial_frame

    partial = PartialConfig(seed=config.seed, frames=config.frames)
    cases = []
    for distance_m in config.distances_m:
        for index in range(config.frames):
            frame, beacon_map, options, _ = partial_frame(partial, scale, distance_m, index)
            cases.append(_locate_case(frame, beacon_map, options, _full_size(frame.pixels, reference),
                                      config.gravity))
    return cases


def shape_speed_cases(config: SpeedConfig, key: str, scale: float, reference: np.ndarray) -> list[Case]:
    from simulator.bench_shapes import ShapesConfig, shape_frame

    shapes = ShapesConfig(seed=config.seed, scale=scale)
    cases = []
    for index in range(config.frames * len(config.distances_m)):
        drawn = shape_frame(shapes, key, index)
        cases.append(_locate_case(drawn.frame, drawn.beacon_map, drawn.options,
                                  _full_size(drawn.frame.pixels, reference), config.gravity))
    return cases


# the app cuts an ID frame to its burst's pose window grown by these shares of that window's height and width
# on each side, rounded up (android_client FramePipeline.idWindow, Window.grown): the panel moves until the
# burst's last ID frame
ID_WINDOW_ROW_GROWTH = 0.25
ID_WINDOW_COLUMN_GROWTH = 0.1


def id_window(pose_window: tuple[int, int, int, int], width: int, height: int) -> tuple[int, int, int, int]:
    """The window (x0, y0, x1, y1) the app cuts a burst's ID frames to from its pose frame's window."""
    x0, y0, x1, y1 = pose_window
    grow_x, grow_y = math.ceil(ID_WINDOW_COLUMN_GROWTH * (x1 - x0)), math.ceil(ID_WINDOW_ROW_GROWTH * (y1 - y0))
    return max(0, x0 - grow_x), max(0, y0 - grow_y), min(width, x1 + grow_x), min(height, y1 + grow_y)


# scripts/android_bench.sh's scene (AndroidBench.SCENE), not the bundled one-panel `android-bench`
ANDROID_BENCH_SCENE = (Path(__file__).resolve().parents[1]
                       / "android_client/core/src/test/resources/replay/android-bench.json")


@dataclass(frozen=True)
class Capture:
    """A device's capture as the server receives it: upload order (ID frames first, then the pose frame)."""

    whole: list[LumaFrame]  # the frames uncut
    windows: list[LumaFrame]  # as the app sends them


def android_captures(config: SpeedConfig) -> tuple[list[Capture], BeaconMap]:
    """`frames` x the distances' count captures of the Android bench's scene (ANDROID_BENCH_SCENE: two coded
    panels, so that the phone takes ID bursts and the server decodes them), `config.distances_m[0]` below its
    first panel, half a second apart as that bench renders them (`simulate --bursts`): a pose frame and its
    4 ID frames each."""
    from lumipose_client.crop import beacon_window, crop_frame
    from simulator.bursts import burst_span_s, capture_starts
    from simulator.sampling import render_capture, series_poses
    from simulator.scene import Scene, load_scene

    scene = load_scene(ANDROID_BENCH_SCENE)
    data = scene.model_dump(by_alias=True)
    ceiling_m = data["beacons"][0]["center_m"][2]
    first = data["series"]["path"]["poses"][0]
    first["position_m"][2] = ceiling_m - config.distances_m[0]
    count = config.frames * len(config.distances_m)
    data["series"]["path"]["poses"] = [{**first, "t_s": 0.5 * k} for k in range(count)]
    scene = Scene.model_validate(data)
    samples = series_poses(scene)
    starts = capture_starts([sample.t_s for sample in samples], burst_span_s(scene))
    captures = []
    for sample, start_s in zip(samples, starts, strict=True):
        rendered = render_capture(scene, sample, start_s)
        (pose_pixels, pose_meta), ids = rendered[0], rendered[1:]
        pose_window = beacon_window(pose_pixels)
        order = [*ids, (pose_pixels, pose_meta)]  # the app sends a burst's ID frames first
        whole = [decode_frame(np.ascontiguousarray(p).tobytes(), m) for p, m in order]
        windows = []
        for pixels, meta in order:
            window = pose_window
            if meta.frame_kind is FrameKind.id and pose_window is not None:
                window = id_window(pose_window, meta.width, meta.height)
            cut_meta, cut = crop_frame(pixels, meta, window)
            windows.append(decode_frame(cut, cut_meta))
        captures.append(Capture(whole, windows))
    return captures, scene.beacon_map()


def _timed_capture(frames: list[LumaFrame], beacon_map: BeaconMap) -> Timed:
    """The frames through `locate` as one device's uploads reach it, in a store where the device is new."""
    devices = Devices()
    start = _clock()
    results = [locate(frame, beacon_map, device_id="speed-bench", devices=devices) for frame in frames]
    return _timed(start, results[-1].ok)


def _timed_id_frame(frame: LumaFrame, beacon_map: BeaconMap) -> Timed:
    devices = Devices()
    start = _clock()
    result = locate(frame, beacon_map, device_id="speed-bench", devices=devices)
    # an ID frame's answer is a refusal that says its stripes were kept
    return _timed(start, "kept" in (result.message or ""))


def id_cases(captures: list[Capture], beacon_map: BeaconMap, window: bool, reference: np.ndarray) -> list[Case]:
    cases = []
    for capture in captures:
        for whole, sent in zip(capture.whole, capture.windows, strict=True):
            if whole.meta.frame_kind is FrameKind.id:
                frame = sent if window else whole
                cases.append(Case(lambda frame=frame: _timed_id_frame(frame, beacon_map),
                                  _full_size(whole.pixels, reference)))
    return cases


def first_capture_cases(captures: list[Capture], beacon_map: BeaconMap, reference: np.ndarray) -> list[Case]:
    return [Case(lambda capture=capture: _timed_capture(capture.windows, beacon_map),
                 _full_size(capture.whole[-1].pixels, reference)) for capture in captures]


def _timed_request(client, data, meta: FrameMeta, map_name: str) -> Timed:
    start = time.perf_counter()
    result: LocateResult = client.locate(data, meta, map=map_name, compress=None)
    request_s = time.perf_counter() - start
    pipeline_s = result.timing_ms.get("total", 0.0) / 1000.0
    return Timed(request_s - pipeline_s, result.ok, request_s=request_s)


@contextmanager
def service_cases(config: SpeedConfig, paths: list[str], reference: np.ndarray) -> Iterator[dict[str, list[Case]]]:
    """The service paths' cases against one fresh `lumipose serve` (one worker), stopped on exit."""
    from lumipose_client.client import Client, encode_frame
    from lumipose_client.crop import crop_frame
    from simulator.bench_service import service_frame
    from simulator.local_server import LocalServer

    with LocalServer("--workers", "1", "--log-level", "warning") as server, \
            Client(server.url, timeout_s=120) as client:
        cases: dict[str, list[Case]] = {path: [] for path in paths}
        for k in range(config.frames * len(config.distances_m)):
            meta, data, beacon_map = service_frame(None, seed=config.seed + 2 + k)
            client.put_map(beacon_map)
            pixels = np.frombuffer(data, np.uint8).reshape(meta.height, meta.width)
            sent = {"service-full": (meta, data), "service-window": crop_frame(pixels, meta)}
            for path in paths:
                path_meta, path_data = sent[path]
                encoded = encode_frame(path_data, None)  # once: the client's copy is not the service's cost
                cases[path].append(Case(lambda m=path_meta, e=encoded, n=beacon_map.name:
                                        _timed_request(client, e, m, n), _full_size(pixels, reference)))
        yield cases


def measure(cases: list[Case], rounds: int, repeats: int) -> dict:
    """Every case once as a warm-up, then `rounds` passes over all, each call `repeats` times, a reference
    pass just before each call; the ratios' medians overall and per round.

    `median_ratio` is wall time over wall time (the issue's figure). `cpu_median_ratio` is this process's
    CPU time over the reference's: a loaded machine preempts a long call and seldom the 3 ms reference, so
    the wall ratio grows with the load while the CPU ratio stays (none for the service, timed from outside).
    """
    out = np.empty_like(cases[0].reference)
    for case in cases:
        case.call()  # first calls allocate and fill caches
    ratios: list[list[float]] = []
    cpu_ratios: list[list[float]] = []
    call_ms, reference_ms, request_ms = [], [], []
    refusals = 0
    for _ in range(rounds):
        ratios.append([])
        cpu_ratios.append([])
        for case in cases:
            if out.shape != case.reference.shape:
                out = np.empty_like(case.reference)
            for _ in range(repeats):
                reference = reference_pass_s(case.reference, out)
                timed = case.call()
                refusals += not timed.ok
                ratios[-1].append(timed.seconds / reference.seconds)
                if timed.cpu_s is not None and reference.cpu_s:
                    cpu_ratios[-1].append(timed.cpu_s / reference.cpu_s)
                call_ms.append(timed.seconds * 1000.0)
                reference_ms.append(reference.seconds * 1000.0)
                if timed.request_s is not None:
                    request_ms.append(timed.request_s * 1000.0)
    every = [r for round_ratios in ratios for r in round_ratios]
    every_cpu = [r for round_ratios in cpu_ratios for r in round_ratios]
    report = {
        "frames": len(cases),
        "median_ratio": statistics.median(every),
        "round_median_ratios": [statistics.median(r) for r in ratios],
        "p90_ratio": float(np.percentile(every, 90)),
        "cpu_median_ratio": statistics.median(every_cpu) if every_cpu else None,
        "cpu_round_median_ratios": [statistics.median(r) for r in cpu_ratios if r],
        "median_ms": statistics.median(call_ms),
        "reference_median_ms": statistics.median(reference_ms),
        "refusals": refusals,
        "calls": len(every),
    }
    if request_ms:
        report["request_median_ms"] = statistics.median(request_ms)
        report["outside_share_pct"] = 100.0 * report["median_ms"] / report["request_median_ms"]
    return report


def _row(path: str, variant: str, measured: dict) -> dict:
    target = TARGETS[(path, variant)]
    return {"path": path, "variant": variant, "label": target.label, "target_ratio": target.ratio,
            **measured, "met": measured["median_ratio"] <= target.ratio}


def _reference_frame(config: SpeedConfig) -> np.ndarray:
    """The full-size frame the reference pass reads for a path whose own frames are smaller."""
    from simulator.benchmarks import AccuracyConfig, accuracy_frame

    return accuracy_frame(AccuracyConfig(distance_m=config.distances_m[0], seed=config.seed), 0)[0].pixels


def _progress(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


def run_speed(config: SpeedConfig) -> dict:
    """Every path of `config.paths`, rendered then measured path by path: the report `bench speed` prints."""
    unknown = sorted(set(config.paths) - set(PATHS))
    if unknown:
        raise ValueError(f"unknown paths {unknown}: use {', '.join(PATHS)}")
    box = machine()  # its load as the run starts; the end's is added below
    reference = _reference_frame(config)
    rows = []

    def measured(path: str, variant: str, cases: list[Case]) -> None:
        _progress(f"speed: {path} ({variant}), {len(cases)} frames x {config.rounds} rounds")
        rows.append(_row(path, variant, measure(cases, config.rounds, config.repeats)))

    builders: dict[tuple[str, str], Callable[[], list[Case]]] = {
        ("square", "full"): lambda: square_cases(config, 1.0, reference),
        ("square-quarter", "quarter"): lambda: square_cases(config, QUARTER, reference),
        ("cut", "quarter"): lambda: cut_cases(config, QUARTER, reference),
        ("cut", "full"): lambda: cut_cases(config, 1.0, reference),
        ("rectangle", "quarter"): lambda: shape_speed_cases(config, "rectangle-1200x300", QUARTER, reference),
        ("rectangle", "full"): lambda: shape_speed_cases(config, "rectangle-1200x300", 1.0, reference),
        ("circle", "quarter"): lambda: shape_speed_cases(config, CIRCLE, QUARTER, reference),
        ("circle", "full"): lambda: shape_speed_cases(config, CIRCLE, 1.0, reference),
    }
    for (path, variant), build in builders.items():
        if path in config.paths:
            _progress(f"speed: rendering {path} ({variant})")
            measured(path, variant, build())
    if {"id-frame", "first-capture"} & set(config.paths):
        _progress("speed: rendering android-bench captures")
        captures, beacon_map = android_captures(config)
        if "id-frame" in config.paths:
            measured("id-frame", "whole", id_cases(captures, beacon_map, False, reference))
            measured("id-frame", "window", id_cases(captures, beacon_map, True, reference))
        if "first-capture" in config.paths:
            measured("first-capture", "window", first_capture_cases(captures, beacon_map, reference))
    service = [path for path in ("service-full", "service-window") if path in config.paths]
    if service:
        _progress("speed: starting lumipose serve")
        with service_cases(config, service, reference) as cases:
            for path in service:
                measured(path, "raw", cases[path])
    order = list(TARGETS)
    rows.sort(key=lambda row: order.index((row["path"], row["variant"])))
    settings = {"paths": list(config.paths), "frames": config.frames, "rounds": config.rounds,
                "repeats": config.repeats, "distances_m": list(config.distances_m), "gravity": config.gravity,
                "seed": config.seed}
    box |= {"load_average_1min_end": os.getloadavg()[0],
            "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    return {"command": speed_command(config), "rows": rows, "config": settings, "machine": box,
            "reference": "cv2.threshold(full 3880x5184 frame, 128, 255, THRESH_BINARY, dst=preallocated), "
                         "cv2.setNumThreads(1) around it only"}


def speed_command(config: SpeedConfig) -> str:
    """The command line that measures `config` again."""
    paths = "all" if set(config.paths) == set(PATHS) else " ".join(config.paths)
    distances = " ".join(f"{d:g}" for d in config.distances_m)
    return (f"lumipose bench speed --path {paths} --frames {config.frames} --rounds {config.rounds} --repeats "
            f"{config.repeats} --distance {distances} --seed {config.seed}{'' if config.gravity else ' --no-gravity'}")


def machine() -> dict:
    """What the figures were measured on: cores, load, versions, the commit."""
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                                cwd=Path(__file__).resolve().parent, timeout=10).stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {"cpu_count": os.cpu_count(), "cpu": _cpu_model(), "load_average_1min": os.getloadavg()[0],
            "when_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), "python": platform.python_version(),
            "numpy": np.__version__, "opencv": cv2.__version__, "cv2_threads": cv2.getNumThreads(),
            "platform": platform.platform(), "commit": commit}


def _cpu_model() -> str | None:
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return platform.processor() or None
    return next((line.split(":", 1)[1].strip() for line in text.splitlines() if line.startswith("model name")), None)


def _ratio(value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return "-"
    return f"{value:.1f}x" if value >= 10 else f"{value:.2f}x"


def _load_end(box: dict) -> str:
    return f"-{box['load_average_1min_end']:.1f}" if "load_average_1min_end" in box else ""


def format_speed(report: dict) -> str:
    """The readable table: each row's median ratio beside its target, its rounds' medians and its time."""
    config, box = report["config"], report["machine"]
    lines = [f"{config['frames']} frames per distance at {config['distances_m']} m, {config['rounds']} rounds x "
             f"{config['repeats']} repeats; {box['cpu_count']} cores, load {box['load_average_1min']:.1f}"
             f"{_load_end(box)}, "
             f"commit {box.get('commit')}",
             "ratio to one reference pass (cv2.threshold, full frame, one thread, preallocated output)",
             f"{'path':<48} {'ratio':>8} {'target':>7} {'met':>5} {'cpu':>8} {'ms':>8}  per round"]
    for row in report["rows"]:
        rounds = " ".join(_ratio(r) for r in row["round_median_ratios"])
        extra = f"  ({row['outside_share_pct']:.0f} % of the request)" if "outside_share_pct" in row else ""
        refusals = f"  {row['refusals']} not ok" if row["refusals"] else ""
        lines.append(f"{row['label']:<48} {_ratio(row['median_ratio']):>8} {_ratio(row['target_ratio']):>7} "
                     f"{'yes' if row['met'] else 'no':>5} {_ratio(row.get('cpu_median_ratio')):>8} "
                     f"{row['median_ms']:8.2f}  {rounds}{extra}{refusals}")
    return "\n".join(lines)


def _wall_cpu(row: dict) -> str:
    cpu = row.get("cpu_median_ratio")
    return _ratio(row["median_ratio"]) + ("" if cpu is None else f" / {_ratio(cpu)}")


def markdown_table(report: dict, before: dict | None = None) -> str:
    """Issue 30's table from a report (after) and a baseline run's report (before), each ratio as wall / CPU,
    beside the issue's own figure (a quiet machine's wall ratio) and the target. Met: the wall ratio, as the
    issue measures it, within the target."""
    before_rows = {(r["path"], r["variant"]): r for r in (before or {}).get("rows", [])}
    lines = ["| path | issue 30 (quiet) | before (wall / CPU) | target | after (wall / CPU) | met |",
             "| --- | --- | --- | --- | --- | --- |"]
    rows = {(r["path"], r["variant"]): r for r in report["rows"]}
    for key, target in TARGETS.items():
        row = rows.get(key)
        old = before_rows.get(key)
        was = "-" if old is None else _wall_cpu(old)
        after = "-" if row is None else _wall_cpu(row)
        met = "-" if row is None else ("yes" if row["met"] else "no")
        cells = [target.label, target.issue_before, was, f"<= {_ratio(target.ratio)}", after, met]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot_speed(report: dict, path: Path, before: dict | None = None) -> None:
    """Bars of each path's ratio (log scale) with its target marked; the baseline's beside them when given."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from simulator.reports import plain_log_axis

    rows = report["rows"]
    before_rows = {(r["path"], r["variant"]): r for r in (before or {}).get("rows", [])}
    x = np.arange(len(rows))
    figure, axis = plt.subplots(figsize=(10, 5))
    width = 0.4 if before_rows else 0.7
    was: list[float] = []
    if before_rows:
        was = [before_rows.get((r["path"], r["variant"]), {}).get("median_ratio", np.nan) for r in rows]
        axis.bar(x - width / 2, was, width, color="#bbbbbb", label="before")
    now = [r["median_ratio"] for r in rows]
    colours = ["#2a7f3f" if r["met"] else "#c0392b" for r in rows]
    axis.bar(x + (width / 2 if before_rows else 0.0), now, width, color=colours, label="measured, wall")
    cpu = [np.nan if r.get("cpu_median_ratio") is None else r["cpu_median_ratio"] for r in rows]
    axis.plot(x + (width / 2 if before_rows else 0.0), cpu, "D", color="black", markersize=5, label="measured, CPU")
    for k, row in enumerate(rows):
        axis.hlines(row["target_ratio"], k - 0.45, k + 0.45, colors="black", linestyles="--",
                    label="target" if k == 0 else None)
    axis.set_yscale("log")
    shown = [v for v in [*now, *[r["target_ratio"] for r in rows], *cpu, *was] if v > 0]
    axis.set_ylim(min(shown) / 2, max(shown) * 2)  # every bar and target inside the axes
    axis.set_xticks(x, [TARGETS[(r["path"], r["variant"])].label for r in rows], rotation=35, ha="right",
                    fontsize=8)
    axis.set_ylabel("time / one cv2.threshold pass (full frame)")
    box = report["machine"]
    axis.set_title(f"cost per path, commit {box.get('commit')}, load {box['load_average_1min']:.0f} on "
                   f"{box['cpu_count']} cores (green: target met)")
    axis.legend(fontsize=8)
    plain_log_axis(axis.yaxis)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def read_report(path: Path) -> dict:
    return json.loads(Path(path).read_text())
