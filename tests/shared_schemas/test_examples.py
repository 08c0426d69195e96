"""The golden examples that other languages test against are valid and say what they claim."""

import json

import numpy as np
import pytest

from server.ingest import read_fixture
from server.locator import locate
from shared_schemas import PACKAGE_DIR, BeaconMap, ErrorBody, FrameMeta, LocateResult, load_map

EXAMPLES = PACKAGE_DIR / "examples"
MODEL_OF = {
    "frame.json": FrameMeta,
    "frame_profile_nv21.json": FrameMeta,
    "map.json": BeaconMap,
    "result_ok.json": LocateResult,
    "result_no_fix.json": LocateResult,
    "error.json": ErrorBody,
}


def test_every_example_has_a_model():
    assert {path.name for path in EXAMPLES.glob("*.json")} == set(MODEL_OF)


@pytest.mark.parametrize("name", sorted(MODEL_OF))
def test_example_validates_and_round_trips(name):
    data = json.loads((EXAMPLES / name).read_text())
    model = MODEL_OF[name].model_validate(data)
    again = json.loads(model.model_dump_json(by_alias=True, exclude_unset=True))
    assert again == data


def test_ok_result_is_what_the_pipeline_gives_for_the_example_frame():
    golden = LocateResult.model_validate_json((EXAMPLES / "result_ok.json").read_text())
    result = locate(read_fixture("tests/fixtures/bench_1m.json"), load_map())
    assert json.loads((EXAMPLES / "frame.json").read_text()) == json.loads(
        open("tests/fixtures/bench_1m.json").read())
    assert result.ok and golden.ok
    # Loose enough for pipeline tuning, tight enough to catch a changed convention.
    np.testing.assert_allclose(result.position_m, golden.position_m, atol=1e-3)
    np.testing.assert_allclose(result.corners_px, golden.corners_px, atol=0.2)
