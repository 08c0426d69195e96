"""A phone walking the paper's office through the real server: ID frames and pose frames uploaded
separately with X-Lumipose-Device, combined by the device's session (rendered, fixed seed)."""

import numpy as np
import pytest

from lumipose_client import Client
from simulator.local_server import LocalServer
from simulator.bench_office import OfficeConfig, office_scenes, true_beacon, walk_captures
from shared_schemas import FrameKind


def _upload(client: Client, frame, device: str | None, map_name: str):
    return client.locate(np.ascontiguousarray(frame.pixels).tobytes(), frame.meta, map=map_name, compress=None,
                         **({"device": device} if device else {}))


@pytest.fixture(scope="module")
def roomy_server_url():
    with LocalServer("--log-level", "warning") as server:  # the default upload limit: pose frames are 5 MB
        yield server.url
    assert "Traceback" not in server.log(), server.log()


def test_a_walk_gets_fixes_with_the_right_ids_and_a_track(roomy_server_url):
    config = OfficeConfig(walk="zigzag", max_captures=5, pose_scale=0.5, seed=2)
    pose_scene, _ = office_scenes(config)
    beacon_map = pose_scene.beacon_map()
    fixes, id_answers = [], []
    with Client(roomy_server_url) as client:
        client.put_map(beacon_map)
        for capture in walk_captures(config):
            for id_frame in capture.id_frames:
                id_answers.append(_upload(client, id_frame, "phone-7", beacon_map.name))
            result = _upload(client, capture.pose_frame, "phone-7", beacon_map.name)
            if result.ok:
                truth = true_beacon(list(beacon_map.beacons), pose_scene.camera.intrinsics(), capture.pose,
                                    result.center_px)
                error_mm = 1000 * np.hypot(*np.subtract(result.position_m[:2], capture.pose.position_m[:2]))
                fixes.append((result, truth, error_mm))
        stateless = _upload(client, capture.pose_frame, None, beacon_map.name)

    assert all(not a.ok and a.reason.value == "id_frame" and "kept" in a.message for a in id_answers)
    assert len(fixes) >= 3, "the session gave too few fixes"
    assert all(result.beacon_id == truth for result, truth, _ in fixes)
    assert all(result.track is not None and result.beacon_id_source.value in ("vlc", "track")
               for result, _, _ in fixes)
    assert np.mean([error for _, _, error in fixes]) < 10.0
    # without a device the 8.4 ms pose frame alone carries no ID in a room of four beacons
    assert not stateless.ok and stateless.reason.value == "unknown_beacon"


def test_many_devices_at_once_lose_no_state_and_get_no_error(server_url, client):
    """120 devices from 8 threads over real HTTP, each a burst of ID frames, a pose frame, a burst
    again: every ID frame must find the ones its device sent before (its record kept, not another's)."""
    from concurrent.futures import ThreadPoolExecutor

    from tests.helpers import ROOM, dark_frame

    client.put_map(ROOM)
    bursts, devices = 4, 120

    def walk(device: str) -> list[str]:
        problems = []
        with Client(server_url) as own:
            for round_ in range(2):
                for n in range(bursts):
                    frame = dark_frame(FrameKind.id, round_ + 0.01 * n)
                    answer = _upload(own, frame, device, ROOM.name)
                    if not answer.message.endswith(f"({n + 1} waiting)"):
                        problems.append(f"{device}: {answer.message}")
                pose = _upload(own, dark_frame(FrameKind.pose, round_ + 0.1), device, ROOM.name)
                if pose.reason is None or pose.reason.value != "no_beacon":
                    problems.append(f"{device}: pose frame gave {pose.reason}")
        return problems

    with ThreadPoolExecutor(max_workers=8) as pool:
        problems = [p for found in pool.map(walk, [f"crowd-{k}" for k in range(devices)]) for p in found]
    assert problems == []
    assert client.health().status == "ok"
