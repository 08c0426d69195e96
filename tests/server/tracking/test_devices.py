"""Devices: one record per device (lock, session, waiting ID stripes), safe from many threads."""

import sys
import threading

import numpy as np
import pytest

from server.ingest import LumaFrame
from server.tracking.devices import DeviceRules, Devices
from shared_schemas import FrameKind
from tests.helpers import DARK_CAMERA, OTHER_ROOM, ROOM, dark_frame


class Clock:
    def __init__(self):
        self.now = 1000.0

    def __call__(self):
        return self.now


def test_many_devices_from_many_threads_lose_no_session_and_raise_nothing():
    # The store used to rebuild its session dict while holding one device's lock only: 16 threads
    # x 50 devices gave 58 "dictionary changed size during iteration" and 316 lost sessions.
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)  # switch threads often, so any unguarded window shows
    devices, errors = Devices(DeviceRules(max_devices=10_000)), []
    threads, per_thread, frames = 16, 8, 6

    def walk(thread: int) -> None:
        for k in range(per_thread):
            device = f"phone-{thread}-{k}"
            try:
                for n in range(frames):
                    kept = devices.locate(device, dark_frame(FrameKind.id, n), ROOM)
                    assert kept.message.endswith("(1 waiting)"), kept.message
                    devices.locate(device, dark_frame(FrameKind.pose, n), ROOM)
            except Exception as error:  # noqa: BLE001 - every failure is counted, not just the first
                errors.append(repr(error))

    try:
        workers = [threading.Thread(target=walk, args=(t,)) for t in range(threads)]
        for worker in workers:
            worker.start()
        for worker in workers:
            worker.join()
    finally:
        sys.setswitchinterval(interval)
    assert errors == []
    assert len(devices) == threads * per_thread
    lost = [f"phone-{t}-{k}" for t in range(threads) for k in range(per_thread)
            if devices.stats(f"phone-{t}-{k}").captures != frames]
    assert lost == []


def test_id_frames_wait_for_the_next_pose_frame_and_a_new_burst_replaces_an_old_one():
    devices = Devices(DeviceRules(id_frames_kept=4))
    answers = [devices.locate("p", dark_frame(FrameKind.id, 0.01 * n), ROOM).message for n in range(6)]
    assert [a.split("(")[-1] for a in answers] == ["1 waiting)", "2 waiting)", "3 waiting)", "4 waiting)",
                                                   "4 waiting)", "4 waiting)"]
    result = devices.locate("p", dark_frame(FrameKind.pose, 0.1), ROOM)
    assert result.reason.value == "no_beacon"
    assert devices.locate("p", dark_frame(FrameKind.id, 0.2), ROOM).message.endswith("(1 waiting)")


def test_an_id_frame_that_cannot_carry_stripes_is_refused_with_the_reason():
    frame = dark_frame(FrameKind.id)
    slow = LumaFrame(frame.pixels, frame.meta.model_copy(update={"exposure_s": 0.01}), DARK_CAMERA)
    result = Devices().locate("p", slow, ROOM)
    assert not result.ok and result.reason.value == "id_frame" and "not kept" in result.message


def test_idle_devices_are_dropped_with_their_lock_and_session():
    clock = Clock()
    devices = Devices(DeviceRules(idle_s=60.0), clock=clock)
    devices.locate("old", dark_frame(), ROOM)
    clock.now += 30.0
    devices.locate("recent", dark_frame(), ROOM)
    clock.now += 45.0  # "old" idle 75 s, "recent" 45 s
    devices.locate("new", dark_frame(), ROOM)
    assert devices.stats("old") is None and devices.stats("recent") is not None and len(devices) == 2


def test_beyond_max_devices_the_least_recently_seen_give_way():
    devices = Devices(DeviceRules(max_devices=3))
    for name in ("a", "b", "c"):
        devices.locate(name, dark_frame(), ROOM)
    devices.locate("a", dark_frame(t_s=1.0), ROOM)  # "a" seen again: "b" is now the oldest
    devices.locate("d", dark_frame(), ROOM)
    assert len(devices) == 3 and devices.stats("b") is None
    assert devices.stats("a").captures == 2


def test_a_new_map_starts_a_new_session():
    devices = Devices()
    devices.locate("p", dark_frame(), ROOM)
    devices.locate("p", dark_frame(t_s=0.5), ROOM)
    assert devices.stats("p").captures == 2
    devices.locate("p", dark_frame(t_s=1.0), OTHER_ROOM)
    assert devices.stats("p").captures == 1


@pytest.mark.parametrize("kind", [FrameKind.pose, FrameKind.id])
def test_a_failing_request_still_returns_the_device_record(kind, monkeypatch):
    def fail(*args, **kwargs):
        raise RuntimeError("stage failed")

    monkeypatch.setattr("server.tracking.devices.read_id_frame", fail)
    monkeypatch.setattr("server.tracking.devices.DeviceSession.locate", fail)
    devices = Devices(DeviceRules(max_devices=1))
    with pytest.raises(RuntimeError):
        devices.locate("p", dark_frame(kind), ROOM)
    monkeypatch.undo()
    devices.locate("q", dark_frame(), ROOM)  # "p" is no longer in use, so it gives way to "q"
    assert len(devices) == 1 and devices.stats("q") is not None


def test_waiting_stripes_are_bounded_in_bytes_across_devices(monkeypatch):
    from server.vlc.decoder import StripeObservation
    from server.vlc.reader import IdFrameReading, PanelStripes

    rows = 3000  # a big panel's stripes: ~100 KB each
    observation = StripeObservation(0.0, 1 / 8000, np.zeros((rows, 4)), np.zeros(rows), np.zeros(rows),
                                    np.zeros(rows), 20.0)
    panels = tuple(PanelStripes(None, (0.5, 0.5), observation) for _ in range(20))  # a frame full of panels
    monkeypatch.setattr("server.tracking.devices.read_id_frame", lambda *a: IdFrameReading(panels, None))
    per_frame = 8 * (observation.nbytes + 256) + 128  # only the 8 largest panels keep their stripes
    devices = Devices(DeviceRules(max_panels_per_id_frame=8, max_waiting_bytes=3 * per_frame))
    for k in range(5):
        devices.locate(f"phone-{k}", dark_frame(FrameKind.id), ROOM)
        assert devices.waiting_bytes <= 3 * per_frame
    assert devices.waiting_bytes == 3 * per_frame  # the two least recently seen devices gave theirs up
    devices.locate("phone-4", dark_frame(FrameKind.pose), ROOM)  # its pose frame takes its stripes
    assert devices.waiting_bytes == 2 * per_frame


def test_a_pose_frame_that_fails_still_gives_its_stripes_back_to_the_budget(monkeypatch):
    """The byte count is settled even when the session raises (the locator turns that into a refusal one level
    up): it once stayed at the used-up stripes' size until the device's next frame."""
    from server.tracking.session import DeviceSession

    devices = Devices()
    devices.locate("p", dark_frame(FrameKind.id), ROOM)

    def fails(*args, **kwargs):
        raise FloatingPointError("a numerical failure deep in the fit")

    monkeypatch.setattr(DeviceSession, "locate", fails)
    with pytest.raises(FloatingPointError):
        devices.locate("p", dark_frame(FrameKind.pose), ROOM)
    assert devices.waiting_bytes == 0
