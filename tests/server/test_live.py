"""The live board (server/live.py): what the operator page shows of each device, bounded, from many threads."""

import asyncio
import threading

import numpy as np
import pytest

from server.annotate import FrameSeen
from server.live import BoardFull, LiveBoard, LiveRules
from shared_schemas import FailureReason, LocateResult, TrackState


class Clock:
    def __init__(self, t: float = 1000.0):
        self.t = t

    def __call__(self) -> float:
        return self.t


def fix(x: float, y: float = 0.0, filtered: tuple | None = None) -> LocateResult:
    track = None if filtered is None else TrackState(filtered_position_m=list(filtered), velocity_mps=[0, 0, 0],
                                                     outlier=False)
    return LocateResult(ok=True, position_m=[x, y, 0.0], beacon_id=7, track=track)


def refusal(reason: FailureReason) -> LocateResult:
    return LocateResult(ok=False, reason=reason, message=str(reason))


def seen(nbytes: int = 10_000) -> FrameSeen:
    side = int(nbytes ** 0.5)
    return FrameSeen(size=(640, 480), part=(10, 20, 10 + side, 20 + side), part_pixels=np.zeros((side, side), np.uint8),
                     step=1, close_ups=(), thumbnail=None, sights=())


def test_a_device_shows_its_counts_rate_refusals_latency_and_filtered_track():
    clock = Clock()
    board = LiveBoard(LiveRules(window_s=10.0), clock=clock)
    board.record("phone", "office", fix(1.0, filtered=(0.9, 0.1, 0.0)), latency_ms=12.5)
    clock.t += 1
    board.record("phone", "office", refusal(FailureReason.id_frame))  # an ID frame: counted apart
    board.record("phone", "office", refusal(FailureReason.no_beacon), latency_ms=3.0)
    board.record("phone", "office", fix(2.0), latency_ms=8.0)
    clock.t += 20  # the first fix leaves the window
    board.record("phone", "office", refusal(FailureReason.no_beacon))
    (device,) = board.devices()[1].devices
    assert (device.frames, device.id_frames, device.fixes) == (4, 1, 2)
    assert device.refused == {"no_beacon": 1.0}  # the last 10 s: one pose frame, refused
    assert device.fix_rate_hz == 0.0
    assert device.last_latency_ms is None and device.last.reason is FailureReason.no_beacon
    assert [p[1:] for p in device.track] == [(0.9, 0.1, 0.0), (2.0, 0.0, 0.0)]  # filtered when tracked


def test_shares_and_rate_cover_the_window_only():
    clock = Clock()
    board = LiveBoard(LiveRules(window_s=10.0), clock=clock)
    for reason in (None, None, FailureReason.no_beacon, FailureReason.pose_uncertain):
        board.record("phone", "m", fix(0) if reason is None else refusal(reason))
    (device,) = board.devices()[1].devices
    assert device.fix_rate_hz == pytest.approx(0.2)
    assert device.refused == pytest.approx({"no_beacon": 0.25, "pose_uncertain": 0.25})


def test_updates_since_a_version_carry_only_changed_devices_and_new_track_points():
    board = LiveBoard()
    board.record("a", "m", fix(0.0))
    board.record("b", "m", fix(1.0))
    version, first = board.devices()
    assert [d.device for d in first.devices] == ["b", "a"]  # most recent first
    board.record("a", "m", fix(0.5))
    version2, update = board.devices(version)
    assert [d.device for d in update.devices] == ["a"]
    assert [p[1] for p in update.devices[0].track] == [0.5]  # the page appends it to what it holds
    assert board.devices(version2)[1].devices == []
    assert [p[1] for p in board.devices()[1].devices[0].track] == [0.0, 0.5]  # whole tracks when asked whole


def test_tracks_and_kept_frames_are_bounded_per_device():
    board = LiveBoard(LiveRules(frames_kept=3, track_points=5))
    for i in range(12):
        board.record("phone", "m", fix(float(i)), seen=seen())
    (device,) = board.devices()[1].devices
    assert [p[1] for p in device.track] == [7.0, 8.0, 9.0, 10.0, 11.0]
    kept = board.kept_frames("phone")
    seqs = [k.seq for k in kept]
    assert seqs[0] - seqs[2] == 2 and seqs == sorted(seqs, reverse=True) and device.frames_kept == seqs[::-1]
    assert board.frame_bytes == sum(k.nbytes for k in kept)


def kept_size(result: LocateResult) -> int:
    """What a kept frame counts against the byte budget: its picture's sources and its result."""
    return seen().nbytes + len(result.model_dump_json())


def test_the_byte_budget_drops_the_least_recently_seen_devices_pictures_first():
    one = kept_size(fix(0))
    board = LiveBoard(LiveRules(frames_kept=3, max_frame_bytes=4 * one))
    for device in ("old", "new"):
        for i in range(3):
            board.record(device, "m", fix(i), seen=seen())
    assert len(board.kept_frames("new")) == 3 and len(board.kept_frames("old")) == 1
    assert board.frame_bytes == 4 * one
    board.record("old", "m", fix(9), seen=seen())  # now the most recent: 'new' gives way
    assert len(board.kept_frames("old")) == 2 and len(board.kept_frames("new")) == 2


def test_nothing_is_kept_with_frames_kept_zero_and_devices_are_bounded():
    board = LiveBoard(LiveRules(frames_kept=0, max_devices=3))
    for n in range(5):
        board.record(f"phone-{n}", "m", fix(0), seen=seen())
    assert len(board) == 3 and board.frame_bytes == 0
    assert board.kept_frames("phone-0") is None and board.kept_frames("phone-4") == []
    assert board.picture("phone-4", 1) is None


def test_many_threads_record_at_once_and_every_count_adds_up():
    one = kept_size(fix(100))
    board = LiveBoard(LiveRules(frames_kept=2, max_frame_bytes=10 * one, max_devices=50))
    devices, per_thread, threads = 12, 150, 8
    barrier = threading.Barrier(threads)

    def work(n: int) -> None:
        barrier.wait()
        for i in range(per_thread):
            device = f"phone-{(n + i) % devices}"
            result = fix(i) if i % 3 else refusal(FailureReason.no_beacon)
            board.record(device, "m", result, latency_ms=1.0, seen=seen())
            if i % 10 == 0:
                board.devices(i)
                board.kept_frames(device)

    workers = [threading.Thread(target=work, args=(n,)) for n in range(threads)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    live = board.devices()[1].devices
    assert sum(d.frames for d in live) == threads * per_thread
    assert sum(d.fixes for d in live) == threads * sum(1 for i in range(per_thread) if i % 3)
    kept = [k for d in live for k in board.kept_frames(d.device)]
    assert board.frame_bytes == sum(k.nbytes for k in kept) <= 10 * one
    assert len({k.seq for k in kept}) == len(kept)


def test_a_listener_on_the_event_loop_is_woken_by_a_record_from_another_thread():
    board = LiveBoard()

    async def wait_for_a_record() -> bool:
        with board.listen() as changed:
            threading.Timer(0.05, board.record, args=("phone", "m", fix(0))).start()
            await asyncio.wait_for(changed.wait(), timeout=5)
            return changed.is_set()

    assert asyncio.run(wait_for_a_record())
    assert board.devices()[1].devices[0].device == "phone"


def test_frame_numbers_differ_across_restarts_so_cached_pictures_are_never_another_frames():
    first, restarted = LiveBoard(), LiveBoard()  # a browser caches /frames/<seq>.png by its number
    first.record("cam", "m", fix(0), seen=seen())
    restarted.record("cam", "m", fix(0), seen=seen())
    assert first.kept_frames("cam")[0].seq != restarted.kept_frames("cam")[0].seq


def test_a_device_gone_quiet_is_sent_again_with_its_rate_going_to_zero():
    clock = Clock()
    board = LiveBoard(LiveRules(window_s=10.0), clock=clock)
    board.record("quiet", "m", fix(0))
    version, _ = board.devices()
    clock.t += 5
    board.expire_windows()
    assert board.devices(version)[1].devices == []  # still within its window: nothing to send
    clock.t += 6
    board.expire_windows()
    (device,) = board.devices(version)[1].devices
    assert device.fix_rate_hz == 0.0 and device.refused == {} and device.track == []


def test_a_kept_results_text_counts_against_the_byte_budget():
    one = kept_size(fix(0))
    board = LiveBoard(LiveRules(frames_kept=3, max_frame_bytes=4 * one))
    wordy = LocateResult(ok=False, reason=FailureReason.no_beacon, message="m" * 1000, warnings=["w" * 300] * 8)
    board.record("wordy", "m", wordy, seen=seen())
    assert board.frame_bytes == seen().nbytes + len(wordy.model_dump_json()) > one + 3000


def test_the_shared_json_is_built_once_per_version_and_agrees_from_many_threads():
    board = LiveBoard(LiveRules(max_devices=200))
    for n in range(100):
        board.record(f"phone-{n}", "m", fix(n))
    answers: list[tuple[int, bytes | None]] = []
    barrier = threading.Barrier(8)

    def read(n: int) -> None:
        barrier.wait()
        for i in range(40):
            if n == 0 and i % 4 == 0:
                board.record(f"phone-{i}", "m", fix(i))  # the board changes while the others read
            answers.append(board.shared_json(0))

    workers = [threading.Thread(target=read, args=(n,)) for n in range(8)]
    for worker in workers:
        worker.start()
    for worker in workers:
        worker.join()
    by_version: dict[int, set[int]] = {}
    for version, data in answers:
        by_version.setdefault(version, set()).add(id(data))
        assert data is not None and data.count(b'"device":') == 100
    assert all(len(ids) == 1 for ids in by_version.values())  # one build per version, shared by every reader
    version, _ = board.shared_json(0)
    assert board.shared_json(version) == (version, None)  # nothing changed since: no event


def test_listeners_are_bounded():
    board = LiveBoard(LiveRules(max_listeners=2))

    async def listen_three() -> str:
        with board.listen(), board.listen():
            try:
                with board.listen():
                    return "third opened"
            except BoardFull as full:
                return str(full)

    assert "2 event streams are open" in asyncio.run(listen_three())
