"""A live room for the operator's page: a real `lumipose serve`, a simulated walk under four panels fed
to it by real HTTP, and headless Debian Chromium (Playwright) to look at the page.

Used by tests/dashboard/conftest.py and by `python -m tests.dashboard.screenshots` (docs/dashboard.md).
The walk is the office scene (simulator/scenes/office.json: four coded panels, 17, 42, 99, 200) without
its window, walked round the four panels' centres at 0.25 m/s, one capture (a pose frame and its ID frames)
every 3 s, rendered once at a fifth of the Mi 8 front camera's resolution (ID frames at a tenth).
"""

from __future__ import annotations

import contextlib
import itertools
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from lumipose_cli.main import main as lumipose
from lumipose_client import Client, read_fixture_files
from shared_schemas import BeaconMap, FrameKind, FrameMeta, LocateResult, load_map
from shared_schemas.captures import bursts_in_upload_order
from simulator.local_server import LocalServer
from simulator.scene import find_scene

API_KEY = "dashboard-key"
SCALE = 0.2  # of the Mi 8 front camera's 3880 x 5184: the pipeline stays cheap on 2 cores
CAPTURES = 8  # one lap: 6 m at 0.25 m/s, a capture every 3 s (the 9th would be the start again)
# the four panels' centres, in a loop: the walk passes right under each one
LAP_M = [[-0.6, -0.9], [0.6, -0.9], [0.6, 0.9], [-0.6, 0.9], [-0.6, -0.9]]
DEVICES = ("walker-a", "walker-b")  # walker-b walks the same lap half a lap behind
# wall time between one device's captures as fed (the walk's own clock: 3 s); a capture in the room costs the
# service 0.2-0.9 s of CPU (VLC decoding, outline fits): two devices at this pace keep about half a core busy
CAPTURE_PERIOD_S = 1.5
BENCH_CELL_M = 0.05  # the paper's grid
BENCH_STORED = (0, 2, 3, 5, 7)  # of the bench's row of eight frames, stored as samples
BENCH_DARK = 1  # stored dark: a cell without a fix (frames 4 and 6: not sampled)
SCREENSHOTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "screenshots"
TIMEOUT_MS = 15_000  # the longest a browser test waits for the page to show something
CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]


@dataclass(frozen=True)
class Capture:
    """One capture of the walk: its frames in upload order (ID frames, then the pose frame) and the truth."""

    frames: tuple[tuple[FrameMeta, bytes], ...]
    truth_m: tuple[float, float, float]
    pose_meta: FrameMeta  # the pose frame's metadata: camera and ground truth (position, rotation)


@dataclass(frozen=True)
class Walk:
    map_path: Path
    beacon_map: BeaconMap
    captures: tuple[Capture, ...]
    lap_s: float  # the walk's own clock: one lap (the last capture leads back to the first)


def walk_scene_json() -> str:
    """The office scene without its window (light pollution costs most of the render time), walking the lap
    slowly (motion blur costs most of the rest: each frame is drawn at many instants of its exposure)."""
    scene = find_scene("office")
    path = scene.series.path.model_copy(update={"kind": "waypoints", "points_m": LAP_M, "area_m": None,
                                                "speed_mps": 0.25, "frame_interval_s": 3.0})
    series = scene.series.model_copy(update={"path": path})
    return scene.model_copy(update={"light_sources": [], "series": series}).to_json()


def render_walk(folder: Path, workers: int = 2) -> Walk:
    """Render the lap's captures as fixtures into `folder` (`lumipose simulate SCENE --bursts`) and read them."""
    scene_path = folder / "walk-scene.json"
    scene_path.write_text(walk_scene_json())
    out = folder / "walk"
    command = ["simulate", str(scene_path), str(out), "--limit", str(CAPTURES), "--scale", str(SCALE), "--bursts",
               "--workers", str(workers)]
    if lumipose(command) != 0:
        raise RuntimeError(f"lumipose {' '.join(command)} failed")
    frames = [read_fixture_files(path) for path in sorted(out.glob("office_*.json"))]  # as shot
    captures = []
    for burst in bursts_in_upload_order([meta.frame_kind or FrameKind.pose for meta, _ in frames]):
        pose_meta = frames[burst[-1]][0]
        assert pose_meta.frame_kind is FrameKind.pose and pose_meta.ground_truth is not None
        truth = tuple(pose_meta.ground_truth.position_m)
        captures.append(Capture(tuple(frames[k] for k in burst), truth, pose_meta))
    stamps = [capture.pose_meta.timestamp_ns or 0 for capture in captures]
    lap_s = (stamps[-1] - stamps[0]) * 1e-9 / (len(stamps) - 1) * len(stamps)
    return Walk(out / "map.json", load_map(out / "map.json"), tuple(captures), lap_s)


@dataclass(frozen=True)
class Posted:
    """A pose frame as fed: which device, which capture of the walk, and the service's answer."""

    device: str
    capture: int
    result: LocateResult


@dataclass
class Feeder:
    """Posts the walk for each device from a thread, lap after lap, one capture every `period_s`.

    Each capture's frames go as the app sends them (ID frames first, `X-Lumipose-Device`); every lap
    moves the frames' timestamps on by the walk's lap, so each device's clock only grows."""

    url: str
    walk: Walk
    devices: tuple[str, ...] = DEVICES
    period_s: float = CAPTURE_PERIOD_S
    posted: list[Posted] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)
    _stop: threading.Event = field(default_factory=threading.Event)
    _running: threading.Event = field(default_factory=threading.Event)
    _posting: threading.Lock = field(default_factory=threading.Lock)
    _thread: threading.Thread | None = None

    def start(self) -> Feeder:
        self._running.set()
        self._thread = threading.Thread(target=self._run, name="walk-feeder", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        self._running.set()
        if self._thread is not None:
            self._thread.join(timeout=10)

    @contextlib.contextmanager
    def paused(self) -> Iterator[None]:
        """No capture is posted inside (one being posted is finished first): the live board holds still."""
        self._running.clear()
        with self._posting:
            pass
        try:
            yield
        finally:
            self._running.set()

    def wait_for_fixes(self, count: int, timeout_s: float = 20.0) -> None:
        """Until every device has `count` fixes (raises on a feeder error or the timeout)."""
        deadline = time.monotonic() + timeout_s
        while any(sum(p.result.ok for p in self.posted if p.device == d) < count for d in self.devices):
            if self.errors or time.monotonic() > deadline:
                raise RuntimeError(f"the walk feeder: {self.errors or 'too few fixes'} after {len(self.posted)} posts")
            time.sleep(0.05)

    def _run(self) -> None:
        count = len(self.walk.captures)
        offsets = [k * count // len(self.devices) for k in range(len(self.devices))]
        next_at = time.monotonic()
        with Client(self.url) as client:
            for step in itertools.count():
                self._running.wait()
                if self._stop.is_set():
                    return
                with self._posting:
                    for device, offset in zip(self.devices, offsets, strict=True):
                        lap, capture = divmod(step + offset, count)
                        try:
                            self._post(client, device, capture, round(lap * self.walk.lap_s * 1e9))
                        except Exception as error:  # noqa: BLE001 - reported by wait_for_fixes and the session's end
                            self.errors.append(f"{device} capture {capture}: {error!r}")
                            return
                next_at = max(next_at + self.period_s, time.monotonic())
                if self._stop.wait(max(0.0, next_at - time.monotonic())):
                    return

    def _post(self, client: Client, device: str, capture: int, shift_ns: int) -> None:
        for meta, data in self.walk.captures[capture].frames:
            moved = meta.model_copy(update={"timestamp_ns": (meta.timestamp_ns or 0) + shift_ns})
            result = client.locate(data, moved, map=self.walk.beacon_map.name, device=device, compress=None)
            if moved.frame_kind is FrameKind.pose:
                self.posted.append(Posted(device, capture, result))


def start_server(data_dir: Path, map_path: Path) -> LocalServer:
    """`lumipose serve` with the map of `map_path` active and an API key (the caller enters and leaves it)."""
    return LocalServer("--api-key", API_KEY, "--map", str(map_path), "--log-level", "warning", data_dir=data_dir)


def render_bench(folder: Path) -> list[Path]:
    """The paper's bench (one panel 1 m up): a row of eight grid cells' frames rendered into `folder`, with
    its map.json; the frames' fixtures in the row's order."""
    command = ["simulate", "paper-bench", str(folder), "--limit", "8", "--scale", str(SCALE), "--workers", "1"]
    if lumipose(command) != 0:
        raise RuntimeError(f"lumipose {' '.join(command)} failed")
    return sorted(folder.glob("paper-bench_*.json"))


def cell_label(meta: FrameMeta) -> str:
    """The 'i,j' grid cell of a frame's true position."""
    assert meta.ground_truth is not None
    x_m, y_m = meta.ground_truth.position_m[:2]
    return f"{round(x_m / BENCH_CELL_M)},{round(y_m / BENCH_CELL_M)}"


def store_bench_samples(url: str, frames: list[Path]) -> list[str]:
    """Store the `BENCH_STORED` frames, each labelled with its cell, and frame `BENCH_DARK` dark (its pixels
    zeroed: no fix); the others' cells stay not sampled. Returns every frame's cell label, in order."""
    read = [read_fixture_files(path) for path in frames]
    with Client(url, api_key=API_KEY) as client:
        for k in BENCH_STORED:
            client.store_sample(read[k][1], read[k][0], label=cell_label(read[k][0]))
        dark_meta, data = read[BENCH_DARK]
        client.store_sample(bytes(len(data)), dark_meta, label=cell_label(dark_meta))
    return [cell_label(meta) for meta, _ in read]


def open_view(page, url: str, view: str) -> None:
    """Open the page of the service at `url` on `view` ('live', 'frame/walker-a', ...) and wait for the view."""
    page.goto(f"{url}/dashboard/#{view}")
    page.get_by_test_id(f"view-{view.split('/')[0]}").wait_for(state="visible", timeout=TIMEOUT_MS)


@contextlib.contextmanager
def chromium() -> Iterator:
    """Debian's headless Chromium through Playwright (never a downloaded browser)."""
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            yield browser
        finally:
            browser.close()

