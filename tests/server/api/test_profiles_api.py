"""Device profiles over real HTTP: stored beside the bundled ones, named by frames, never a 500."""

from concurrent.futures import ThreadPoolExecutor
from contextlib import suppress

import httpx
import numpy as np
import pytest

from lumipose_client import Client, LumiposeError
from server.store import ProfileStore
from simulator.local_server import LocalServer
from tests.conftest import API_KEY
from tests.helpers import CALIBRATED, DATASHEET, calibrated_lens_frame

POSITION_M = (0.05, -0.03, 0.0)
MAP = "test-bench"  # the bundled demo map: the panel the frames are rendered from


def _refusal(call) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call()
    return refused.value


def _error_mm(result, position_m=POSITION_M) -> float:
    assert result.ok, result.message
    return 1000 * float(np.linalg.norm(np.subtract(result.position_m, position_m)))


def _named(profile_id: str, **update):
    return CALIBRATED.model_copy(update={"id": profile_id, **update})


def test_profiles_put_get_list_delete(client):
    stored = _named("api-calibrated")
    assert client.put_profile(stored) == stored
    assert client.profile("api-calibrated") == stored
    assert client.profile("xiaomi-mi8-front").intrinsics is None  # bundled ones as before
    summaries = {summary.id: summary for summary in client.profiles()}
    assert summaries["xiaomi-mi8-front"].source == "bundled" and not summaries["xiaomi-mi8-front"].calibrated
    assert summaries["api-calibrated"].source == "stored" and summaries["api-calibrated"].calibrated
    replaced = _named("api-calibrated", name="the same phone, calibrated again")
    assert client.put_profile(replaced) == replaced and client.profile("api-calibrated") == replaced
    client.delete_profile("api-calibrated")
    refused = _refusal(lambda: client.profile("api-calibrated"))
    assert refused.status == 404 and refused.body.error == "not_found"
    assert "known: " in refused.body.message and "xiaomi-mi8-front" in refused.body.message
    assert _refusal(lambda: client.delete_profile("api-calibrated")).status == 404
    assert "api-calibrated" not in {summary.id for summary in client.profiles()}


def test_profile_writes_need_the_key(server_url):
    with Client(server_url) as anonymous:
        for write in (lambda: anonymous.put_profile(_named("keyless")), lambda: anonymous.delete_profile("keyless")):
            refused = _refusal(write)
            assert refused.status == 401 and refused.body.field == "X-API-Key"
        assert _refusal(lambda: anonymous.profile("keyless")).status == 404  # nothing was stored


def test_a_bundled_profile_is_never_replaced_or_deleted(client):
    front = client.profile("xiaomi-mi8-front")
    for write in (lambda: client.put_profile(CALIBRATED.model_copy(update={"id": "xiaomi-mi8-front"})),
                  lambda: client.delete_profile("xiaomi-mi8-front")):
        refused = _refusal(write)
        assert refused.status == 409 and refused.body.error == "bundled_profile", refused.body
        assert "'xiaomi-mi8-front' is a bundled device profile" in refused.body.message
        assert "xiaomi-mi8-front-calibrated" in refused.body.message  # what to do instead
    assert client.profile("xiaomi-mi8-front") == front


def _body(**changes) -> dict:
    body = _named("bad-body").model_dump(mode="json")
    for path, value in changes.items():
        *parents, leaf = path.split("__")
        target = body
        for parent in parents:
            target = target[parent]
        target[leaf] = value
    return body


@pytest.mark.parametrize(
    "path, body, status, error, field",
    [
        ("/v1/profiles/other-id", _body(), 400, "name_mismatch", "id"),
        ("/v1/profiles/bad-body", _body(pixel_size_m=-1e-6), 422, "invalid_request", "pixel_size_m"),
        ("/v1/profiles/bad-body", _body(width=0), 422, "invalid_request", "width"),
        ("/v1/profiles/bad-body", _body(intrinsics__fx=0.0), 422, "invalid_request", "intrinsics.fx"),
        ("/v1/profiles/bad-body", _body(intrinsics__cx=9000.0), 422, "invalid_request", "intrinsics.cx"),
        ("/v1/profiles/bad-body", _body(distortion=[0.1, 0.2, 0.3]), 422, "invalid_request", "distortion"),
        ("/v1/profiles/bad-body", _body(facing="sideways"), 422, "invalid_request", "facing"),
        ("/v1/profiles/bad-body", _body(lens="wide"), 422, "invalid_request", "lens"),
        ("/v1/profiles/bad%20body", _body(id="bad body"), 400, "bad_name", "profile_id"),
    ],
)
def test_bad_profile_bodies_are_refused_naming_the_field(server_url, client, path, body, status, error, field):
    response = httpx.put(f"{server_url}{path}", json=body, headers={"X-API-Key": API_KEY})
    assert (response.status_code, response.json()["error"], response.json()["field"]) == (status, error, field), (
        response.text
    )
    assert "bad-body" not in {summary.id for summary in client.profiles()}


def test_unparsable_profile_bodies_are_refused(server_url):
    headers = {"X-API-Key": API_KEY, "Content-Type": "application/json"}
    for content in (b'{"id": "bad-body", "na', b'{"id": "bad-body", "pixel_size_m": NaN}', b"[]"):
        response = httpx.put(f"{server_url}/v1/profiles/bad-body", content=content, headers=headers)
        assert response.status_code == 422 and response.json()["error"] == "invalid_request", response.text


def test_a_frame_naming_a_stored_profile_is_located_with_it(client):
    meta, data = calibrated_lens_frame(POSITION_M)
    client.put_profile(CALIBRATED)
    try:
        calibrated = _error_mm(client.locate(data, meta, map=MAP))
        client.delete_profile(CALIBRATED.id)
        client.put_profile(DATASHEET)  # the same id without the measured pinhole
        datasheet = _error_mm(client.locate(data, meta, map=MAP))
    finally:
        client.delete_profile(CALIBRATED.id)
    assert calibrated < 3.0 and datasheet > 20.0, (calibrated, datasheet)


def test_a_frame_naming_an_unknown_profile_is_refused_listing_the_known_ones(client):
    meta, data = calibrated_lens_frame(POSITION_M)
    client.put_profile(_named("listed-calibrated"))
    try:
        refused = _refusal(lambda: client.locate(data, meta, map=MAP))
    finally:
        client.delete_profile("listed-calibrated")
    assert refused.status == 400 and refused.body.error == "bad_frame" and refused.body.field == "camera.profile"
    assert refused.body.message.startswith("unknown device profile 'mi8-front-calibrated'; known: ")
    assert {"listed-calibrated", "xiaomi-mi8-front", "xiaomi-mi8-rear"} <= set(
        refused.body.message.split("known: ")[1].split(", ")
    )


def test_a_damaged_stored_profile_is_skipped_reported_and_refused_by_name(tmp_path):
    """Damaged before the server starts (by hand, or a disk), with what an interrupted write leaves."""
    data_dir = tmp_path / "data"
    ProfileStore(data_dir).put(CALIBRATED.id, CALIBRATED)
    ProfileStore(data_dir).put("whole", _named("whole"))
    stored = data_dir / "profiles" / f"{CALIBRATED.id}.json"
    stored.write_bytes(stored.read_bytes()[:80])
    (data_dir / "profiles" / ".whole.json.0123456789abcdef0123456789abcdef.tmp").write_text('{"i')
    meta, data = calibrated_lens_frame(POSITION_M)
    with LocalServer("--api-key", API_KEY, "--log-level", "warning", data_dir=data_dir) as server, Client(
        server.url, api_key=API_KEY
    ) as client:
        assert not list((data_dir / "profiles").glob(".*"))  # the leftover is removed at start-up
        assert f"damaged file in the data folder {data_dir}: profiles/{CALIBRATED.id}.json" in server.log()
        health = client.health()
        assert health.status == "degraded" and health.damaged == [f"profiles/{CALIBRATED.id}.json"]
        assert [s.id for s in client.profiles() if s.source == "stored"] == ["whole"]
        for refused in (_refusal(lambda: client.profile(CALIBRATED.id)), _refusal(lambda: client.locate(data, meta))):
            assert refused.status == 409 and refused.body.error == "damaged_profile", refused.body
            assert f"profiles/{CALIBRATED.id}.json" in refused.body.message
        client.delete_profile(CALIBRATED.id)  # a damaged one can be removed
        assert client.health().status == "ok"
        client.put_profile(CALIBRATED)
        assert _error_mm(client.locate(data, meta, map=MAP)) < 3.0
    assert "Traceback" not in server.log(), server.log()


def test_many_threads_putting_deleting_and_locating_at_once(tmp_path):
    """8 threads on a server of 2 worker processes sharing one data folder: each replaces a shared
    profile, stores, uses, deletes and stores again its own, and locates frames naming both; every
    answer must be the right one (never a torn file, a lost write or a 500)."""
    threads, rounds = 8, 4
    meta, data = calibrated_lens_frame(POSITION_M)

    with LocalServer("--api-key", API_KEY, "--workers", "2", "--log-level", "warning",
                     data_dir=tmp_path / "data") as server:
        def work(thread: int) -> list[str]:
            problems = []
            own_id = f"thread-{thread}"
            own_meta = meta.model_copy(update={"camera": meta.camera.model_copy(update={"profile": own_id})})
            with Client(server.url, api_key=API_KEY) as client:
                for round_ in range(rounds):
                    client.put_profile(CALIBRATED.model_copy(update={"name": f"put by {thread} in {round_}"}))
                    client.put_profile(_named(own_id, name=f"round {round_}"))
                    for named, frame_meta in ((CALIBRATED.id, meta), (own_id, own_meta)):
                        error = _error_mm(client.locate(data, frame_meta, map=MAP))
                        if error > 3.0:
                            problems.append(f"{own_id} round {round_}: {named} located {error:.1f} mm off")
                    if client.profile(own_id).name != f"round {round_}":
                        problems.append(f"{own_id} round {round_}: read back another write")
                    client.delete_profile(own_id)
                    try:
                        client.locate(data, own_meta, map=MAP)
                        problems.append(f"{own_id} round {round_}: located with a deleted profile")
                    except LumiposeError as refused:
                        if refused.body.field != "camera.profile":
                            problems.append(f"{own_id} round {round_}: {refused}")
                    client.profiles()
            return problems

        with ThreadPoolExecutor(max_workers=threads) as pool:
            problems = [problem for found in pool.map(work, range(threads)) for problem in found]
        with Client(server.url) as client:
            health, stored = client.health(), [s.id for s in client.profiles() if s.source == "stored"]
            assert client.profile(CALIBRATED.id).name.startswith("put by ")
    assert problems == []
    assert health.status == "ok" and stored == [CALIBRATED.id]
    assert "Traceback" not in server.log(), server.log()
    assert [path.name for path in (tmp_path / "data" / "profiles").iterdir()] == [f"{CALIBRATED.id}.json"]


def test_a_sample_whose_stored_profile_was_deleted_is_a_row_without_a_fix(client):
    """The evaluation re-locates every sample: one naming a profile deleted since is refused alone."""
    meta, data = calibrated_lens_frame(POSITION_M)
    stored = _named("sampled-calibrated")
    own_meta = meta.model_copy(update={"camera": meta.camera.model_copy(update={"profile": stored.id})})
    client.put_profile(stored)
    sample = client.store_sample(data, own_meta, map=MAP)
    try:
        assert sample.result.ok
        client.delete_profile(stored.id)
        rows = {row.id: row for row in client.evaluate_samples(map=MAP).rows}
        assert not rows[sample.id].ok and rows[sample.id].reason == "bad_frame" and rows[sample.id].error_2d_mm is None
        client.put_profile(stored)
        rows = {row.id: row for row in client.evaluate_samples(map=MAP).rows}
        assert rows[sample.id].ok and rows[sample.id].error_2d_mm < 3.0
    finally:
        client.delete_sample(sample.id)  # the session's other evaluations expect every sample to locate
        with suppress(LumiposeError):
            client.delete_profile(stored.id)
