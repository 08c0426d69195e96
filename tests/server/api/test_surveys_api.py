"""POST /v1/surveys against the real server: stored samples in, the surveyed map out (and stored)."""

from __future__ import annotations

import httpx
import numpy as np
import pytest

from lumipose_client import Client, LumiposeError
from shared_schemas import ProfileRef, device_profiles
from shared_schemas.survey import MAX_SURVEY_FRAMES, PanelLabel, SurveyRequest, SurveySample
from tests.conftest import API_KEY
from tests.helpers import survey_set


@pytest.fixture(scope="module")
def stored(server_url):
    """The quarter-scale office set stored as samples: (truth, sketch, anchor, [(sample ID, labels)])."""
    truth, sketch, anchor, shots = survey_set()
    with Client(server_url, api_key=API_KEY) as client:
        # labelled as the app labels survey photos, which the samples' evaluation leaves out
        samples = [
            (client.store_sample(s.pixels.tobytes(), s.meta, label=f"survey:office:{k}").id, s.labels)
            for k, s in enumerate(shots)
        ]
    return truth, sketch, anchor, samples


def _request(stored, **changes) -> SurveyRequest:
    _, sketch, anchor, samples = stored
    fields = {
        "name": "office-surveyed",
        "sketch": sketch,
        "anchor": anchor,
        "samples": [SurveySample(sample_id=i, labels=labels) for i, labels in samples],
    }
    return SurveyRequest(**(fields | changes))


def _refusal(call) -> LumiposeError:
    with pytest.raises(LumiposeError) as refused:
        call()
    return refused.value


def test_a_survey_of_stored_samples_gives_the_map_and_stores_it(stored, client, server_url):
    truth = stored[0]
    report = client.survey(_request(stored, store=True))
    assert report.stored and report.frames_used >= len(stored[3]) - 2
    for beacon in truth.beacons:
        assert np.linalg.norm(np.subtract(report.map.beacon(beacon.id).center_m, beacon.center_m)) < 0.004
    assert client.get_map("office-surveyed") == report.map
    # the stored map serves as the next survey's sketch, by name
    again = client.survey(_request(stored, sketch="office-surveyed", name="office-again"))
    assert not again.stored and again.map.name == "office-again"
    with Client(server_url) as anonymous:  # storing the map is a write; a survey alone is not
        refused = _refusal(lambda: anonymous.survey(_request(stored, store=True)))
        assert refused.status == 401 and refused.body.field == "X-API-Key"
        refused = _refusal(lambda: anonymous.survey(_request(stored, anchor=7)))
        assert refused.status == 422 and refused.body.field == "anchor"


def test_samples_naming_a_stored_profile_are_surveyed(client):
    """A calibrated profile is stored, not bundled: the survey takes its gravity sigma from the stored table."""
    truth, sketch, anchor, shots = survey_set()
    # the datasheet camera the shots were rendered with, stored under an id of its own (a 0.2 deg sensor)
    stored = device_profiles()["xiaomi-mi8-front"].model_copy(update={"id": "survey-mi8", "gravity_sigma_deg": 0.2})
    client.put_profile(stored)
    named = ProfileRef(profile=stored.id)
    samples = []
    for k, s in enumerate(shots):
        meta = s.meta.model_copy(update={"camera": named})
        stored_id = client.store_sample(s.pixels.tobytes(), meta, label=f"survey:office-profiled:{k}").id
        samples.append(SurveySample(sample_id=stored_id, labels=s.labels))
    request = SurveyRequest(name="office-profiled", sketch=sketch, anchor=anchor, samples=samples)
    report = client.survey(request)
    for beacon in truth.beacons:
        assert np.linalg.norm(np.subtract(report.map.beacon(beacon.id).center_m, beacon.center_m)) < 0.004
    # the profile deleted since: the samples are not damaged, their profile is missing
    client.delete_profile(stored.id)
    refused = _refusal(lambda: client.survey(request))
    assert (refused.status, refused.body.error, refused.body.field) == (404, "not_found", "samples.0.sample_id")
    assert "its camera.profile 'survey-mi8' is no device profile on this server" in refused.body.message


def test_unknown_samples_and_sketches_are_404_naming_the_field(stored, client):
    samples = [SurveySample(sample_id="0" * 32), *_request(stored).samples]
    refused = _refusal(lambda: client.survey(_request(stored, samples=samples)))
    assert refused.status == 404 and refused.body.field == "samples.0.sample_id"
    refused = _refusal(lambda: client.survey(_request(stored, sketch="no-such-room")))
    assert refused.status == 404 and refused.body.field == "sketch" and "no-such-room" in refused.body.message


def test_bad_requests_and_refused_surveys_are_422_naming_what_is_wrong(stored, client):
    refused = _refusal(lambda: client.survey(_request(stored, anchor=7)))
    assert (refused.status, refused.body.field) == (422, "anchor")
    assert "anchor 7 is not in sketch" in refused.body.message
    unknown = PanelLabel(beacon_id=5, x_px=10, y_px=10)
    samples = [SurveySample(sample_id=stored[3][0][0], labels=[unknown])]
    refused = _refusal(lambda: client.survey(_request(stored, samples=samples)))
    assert (refused.status, refused.body.field) == (422, "samples.0.labels.0.beacon_id")
    without_99 = [SurveySample(sample_id=i, labels=[x for x in labels if x.beacon_id != 99]) for i, labels in stored[3]]
    refused = _refusal(lambda: client.survey(_request(stored, samples=without_99)))
    assert refused.status == 422 and refused.body.error == "survey_refused"
    assert "beacon 99 is not connected to anchor 17" in refused.body.message
    one_panel = [SurveySample(sample_id=i, labels=labels[:1]) for i, labels in stored[3][:2]]
    refused = _refusal(lambda: client.survey(_request(stored, samples=one_panel)))
    assert refused.status == 422 and "no frame sees two named panels" in refused.body.message


def test_a_repeated_sample_or_too_many_are_refused_before_any_frame_is_read(stored, server_url):
    body = _request(stored).model_dump(mode="json", by_alias=True)
    body["samples"] = [body["samples"][0], *body["samples"][1:3], body["samples"][0]]
    response = httpx.post(f"{server_url}/v1/surveys", json=body)
    assert response.status_code == 422 and response.json()["field"] == "samples", response.text
    assert "samples 0 and 3 are the same sample" in response.json()["message"]
    body["samples"] = [{"sample_id": f"{k:032x}"} for k in range(MAX_SURVEY_FRAMES + 1)]
    response = httpx.post(f"{server_url}/v1/surveys", json=body)
    assert response.status_code == 422 and response.json()["field"] == "samples", response.text


def test_a_survey_cannot_write_the_map_named_active(stored, client):
    refused = _refusal(lambda: client.survey(_request(stored, name="active", store=True)))
    assert (refused.status, refused.body.error, refused.body.field) == (400, "bad_name", "name")
    assert "'active' is reserved" in refused.body.message
    assert "active" not in {summary.name for summary in client.maps()}


def test_a_malformed_survey_request_is_422(server_url):
    for body, field in (({"name": "x", "anchor": 1, "samples": []}, "sketch"), ({"sketch": "demo"}, "name")):
        response = httpx.post(f"{server_url}/v1/surveys", json=body)
        assert response.status_code == 422 and response.json()["field"] == field, response.text
