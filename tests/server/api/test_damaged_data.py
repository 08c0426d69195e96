"""Files of the data folder damaged while the server was down, and what interrupted writes left:
a real server is stopped, its files are damaged by hand, and it is started again on them
(docs/reliability.md, "Damaged data folder"). Never a 500: damaged files are reported by /healthz
and the log, skipped in listings, refused by name (409), and a damaged sample can be deleted."""

import re
import uuid
from pathlib import Path

import httpx
import pytest

from lumipose_client import Client, LumiposeError
from shared_schemas import load_map
from simulator.local_server import LocalServer
from tests.conftest import API_KEY

SERVE_ARGS = ("--api-key", API_KEY, "--log-level", "warning")


def _refusal(call) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call()
    return refused.value


def _leftovers(data_dir: Path) -> list[str]:
    return sorted(p.relative_to(data_dir).as_posix() for p in data_dir.rglob(".*") if p.name != ".write.lock")


@pytest.fixture(scope="module")
def damaged(tmp_path_factory, fixture_frame):
    """A data folder written by one server, damaged while it was down, served by a second."""
    data_dir = tmp_path_factory.mktemp("damaged")
    meta, frame = fixture_frame
    with LocalServer(*SERVE_ARGS, data_dir=data_dir) as first, Client(first.url, api_key=API_KEY) as client:
        for name in ("office", "lab"):
            client.put_map(load_map().model_copy(update={"name": name}))
        client.set_active_map("office")
        whole = client.store_sample(frame, meta, label="3,-2").id
        broken = client.store_sample(frame, meta, label="3,-2").id
    ghost = uuid.uuid4().hex
    samples = data_dir / "samples"

    (data_dir / "active_map.json").write_text('{"name": "off')
    (data_dir / "maps" / "lab.json").write_bytes((data_dir / "maps" / "lab.json").read_bytes()[:100])
    (samples / broken / "sample.json").write_bytes((samples / broken / "sample.json").read_bytes()[:200])
    # what a crash mid-write leaves: a sample written but not moved into place (the old ghost),
    # a deletion cut short, temporary files of a map and of the active map
    staging = samples / f".{ghost}.tmp"
    staging.mkdir()
    (staging / "frame.bin").write_bytes(frame)
    (staging / "sample.json").write_text((samples / whole / "sample.json").read_text().replace(whole, ghost))
    (samples / f".{whole}.{uuid.uuid4().hex}.deleted").mkdir()
    (data_dir / "maps" / f".office.json.{uuid.uuid4().hex}.tmp").write_text('{"sch')
    (data_dir / f".active_map.json.{uuid.uuid4().hex}.tmp").write_text("")
    assert len(_leftovers(data_dir)) == 4

    with LocalServer(*SERVE_ARGS, data_dir=data_dir) as second:
        yield second, data_dir, whole, broken, ghost
    assert "Traceback" not in second.log(), second.log()


def test_start_up_removes_leftovers_and_logs_what_it_found(damaged):
    server, data_dir, _, broken, _ = damaged
    assert _leftovers(data_dir) == []
    log = server.log()
    removed = re.findall(r"removed (\d+) leftover\(s\) of interrupted writes", log)  # by the map and the sample store
    assert sorted(removed) == ["2", "2"], log
    for name in ("active_map.json", "maps/lab.json", f"samples/{broken}/sample.json"):
        assert f"damaged file in the data folder {data_dir}: {name}" in log, log


def test_healthz_is_degraded_and_names_the_damaged_files(damaged):
    server, _, _, broken, _ = damaged
    response = httpx.get(f"{server.url}/healthz")
    assert response.status_code == 200, response.text
    health = response.json()
    assert health["status"] == "degraded" and health["active_map"] == "test-bench"
    assert health["damaged"] == ["active_map.json", "maps/lab.json", f"samples/{broken}/sample.json"]


def test_a_damaged_active_map_file_means_the_default_map(damaged, fixture_frame):
    server, _, _, _, _ = damaged
    with Client(server.url) as client:
        assert client.active_map().name == "test-bench"
        result = client.locate(fixture_frame[1], fixture_frame[0])
        assert result.ok and result.beacon_id == 0  # the bundled bench map


def test_a_damaged_map_is_left_out_of_the_list_and_refused_by_name(damaged):
    server, _, _, _, _ = damaged
    with Client(server.url) as client:
        assert {m.name for m in client.maps()} == {"test-bench", "office"}
        refused = _refusal(lambda: client.get_map("lab"))
        assert refused.status == 409 and refused.body.error == "damaged_map" and refused.body.field == "name"
        assert "maps/lab.json" in refused.body.message
        assert client.get_map("office").name == "office"
    for path, body in (("/v1/maps/active", {"name": "lab"}),):
        response = httpx.put(f"{server.url}{path}", json=body, headers={"X-API-Key": API_KEY})
        assert response.status_code == 409 and response.json()["error"] == "damaged_map"
    response = httpx.get(f"{server.url}/v1/samples/evaluation", params={"map": "lab"})
    assert response.status_code == 409 and "maps/lab.json" in response.json()["message"]


def test_a_damaged_sample_is_left_out_refused_and_can_be_deleted(damaged):
    server, data_dir, whole, broken, ghost = damaged
    with Client(server.url, api_key=API_KEY) as client:
        assert [s.id for s in client.samples().samples] == [whole]  # neither the damaged one nor the ghost
        evaluation = client.evaluate_samples()
        assert [row.id for row in evaluation.rows] == [whole] and evaluation.coverage == 1.0
        for read in (client.sample, client.sample_frame):
            refused = _refusal(lambda: read(broken))
            assert refused.status == 409 and refused.body.error == "damaged_sample"
            assert f"samples/{broken}/sample.json" in refused.body.message
        assert _refusal(lambda: client.sample(ghost)).status == 404
        client.delete_sample(broken)
        assert not (data_dir / "samples" / broken).exists()
        assert _refusal(lambda: client.sample(broken)).status == 404
        assert _refusal(lambda: client.delete_sample(broken)).status == 404
        assert client.sample(whole).id == whole


def test_files_damaged_while_the_server_runs_are_found_on_read(damaged, fixture_frame):
    """The active map is named, so a frame is refused rather than located in another map."""
    server, data_dir, _, _, _ = damaged
    office = data_dir / "maps" / "office.json"
    with Client(server.url, api_key=API_KEY) as client:
        client.set_active_map("office")
        text = office.read_text()
        office.write_text(text[: len(text) // 2])
        refused = _refusal(lambda: client.locate(fixture_frame[1], fixture_frame[0]))
        assert refused.status == 409 and refused.body.error == "damaged_map" and "maps/office.json" in refused.body.message
        assert "maps/office.json" in client.health().damaged
        client.put_map(load_map().model_copy(update={"name": "office"}))
        assert client.locate(fixture_frame[1], fixture_frame[0]).ok


def test_rewriting_or_deleting_the_damaged_files_clears_the_report(damaged):
    server, _, _, _, _ = damaged
    with Client(server.url, api_key=API_KEY) as client:
        client.set_active_map("office")
        client.put_map(load_map().model_copy(update={"name": "lab"}))
        health = client.health()
        assert health.status == "ok" and health.damaged == [] and health.active_map == "office"
        assert {m.name for m in client.maps()} == {"test-bench", "office", "lab"}
