"""Maps, samples, auth and evaluation against the real server; stored data survives bad writes."""

import httpx
import pytest

from lumipose_client import Client, LumiposeError
from shared_schemas import load_map
from shared_schemas.api import cell_truth_m
from tests.conftest import API_KEY


def _refusal(call) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call()
    return refused.value


def test_maps_list_get_put_and_activate(client):
    names = {summary.name: summary for summary in client.maps()}
    assert names["test-bench"].source == "bundled" and names["test-bench"].active
    office = load_map().model_copy(update={"name": "office-a"})
    assert client.put_map(office) == office
    assert client.get_map("office-a") == office
    assert client.set_active_map("office-a").name == "office-a"
    assert client.active_map().name == "office-a" and client.health().active_map == "office-a"
    refused = _refusal(lambda: client.delete_map("office-a"))
    assert (refused.status, refused.body.error) == (409, "active_map") and "activate another" in refused.body.message
    client.set_active_map("test-bench")
    refused = _refusal(lambda: client.delete_map("test-bench"))
    assert (refused.status, refused.body.error) == (409, "active_map")
    client.delete_map("office-a")
    assert "office-a" not in {summary.name for summary in client.maps()}
    assert _refusal(lambda: client.delete_map("office-a")).status == 404


def test_writes_need_the_key(server_url, fixture_frame):
    office = load_map().model_copy(update={"name": "office-b"})
    with Client(server_url) as anonymous:
        refused = _refusal(lambda: anonymous.put_map(office))
        assert refused.status == 401 and refused.body.field == "X-API-Key"
        assert _refusal(lambda: anonymous.store_sample(fixture_frame[1], fixture_frame[0])).status == 401
    with Client(server_url, api_key="wrong") as wrong:
        assert "wrong" in _refusal(lambda: wrong.put_map(office)).body.message
        assert wrong.maps()  # reads need no key


def test_bad_map_writes_leave_the_stored_map_whole(client, server_url):
    good = load_map().model_copy(update={"name": "office-c"})
    client.put_map(good)
    headers = {"X-API-Key": API_KEY}
    invalid = good.model_dump(mode="json", by_alias=True)
    invalid["beacons"][0]["side_m"] = -1
    for body, status, field in ((invalid, 422, "beacons.0.side_m"),
                                ({**invalid, "name": "other"}, 422, "beacons.0.side_m"),
                                (good.model_dump(mode="json", by_alias=True) | {"name": "other"}, 400, "name")):
        response = httpx.put(f"{server_url}/v1/maps/office-c", json=body, headers=headers)
        assert response.status_code == status and response.json()["field"] == field, response.text
    response = httpx.put(f"{server_url}/v1/maps/office-c", content=b'{"name": "office-c", "beac',
                         headers={**headers, "Content-Type": "application/json"})
    assert response.status_code == 422
    assert client.get_map("office-c") == good
    assert _refusal(lambda: client.get_map("../../etc/passwd")).status in (400, 404)


def test_samples_store_list_fetch_evaluate_delete(client, fixture_frame):
    meta, data = fixture_frame
    truthless = meta.model_copy(update={"ground_truth": None})
    stored = client.store_sample(data, meta, label="3,-2", device="phone-1")
    labelled = client.store_sample(data, truthless, label="3,-2")
    surveyed = client.store_sample(data, truthless, label="survey:office:0")  # left out of the evaluation
    assert stored.result.ok and stored.label == "3,-2" and stored.device == "phone-1"
    ids = [sample.id for sample in client.samples().samples]
    assert stored.id in ids and labelled.id in ids
    fetched_meta, fetched_data = client.sample_frame(stored.id)
    assert fetched_data == data and fetched_meta.ground_truth == meta.ground_truth

    evaluation = client.evaluate_samples(cell_m=0.05)
    rows = {row.id: row for row in evaluation.rows}
    assert rows[stored.id].error_2d_mm < 2.0  # against the frame's own ground truth
    assert rows[labelled.id].truth_m == cell_truth_m("3,-2", 0.05) == pytest.approx([0.15, -0.1, 0.0])
    assert rows[labelled.id].error_2d_mm < 2.0  # the fixture was rendered at that grid cell
    assert evaluation.coverage == 1.0 and evaluation.max_mm < 2.0
    assert surveyed.id not in rows and surveyed.id in [sample.id for sample in client.samples().samples]
    client.delete_sample(surveyed.id)

    client.delete_sample(stored.id)
    assert _refusal(lambda: client.sample(stored.id)).status == 404
    assert _refusal(lambda: client.delete_sample(stored.id)).status == 404
    assert client.sample(labelled.id).id == labelled.id
    client.delete_sample(labelled.id)


def test_profiles(client, server_url):
    assert {profile.id for profile in client.profiles()} >= {"xiaomi-mi8-front", "xiaomi-mi8-rear"}
    response = httpx.get(f"{server_url}/v1/profiles/nokia")
    assert response.status_code == 404 and "xiaomi-mi8-front" in response.json()["message"]
