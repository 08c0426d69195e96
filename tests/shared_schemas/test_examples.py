"""The golden examples that other languages test against are valid and say what they claim."""

import json
from pathlib import Path

import numpy as np
import pytest

from server.ingest import read_fixture
from server.locator import locate
from shared_schemas import PACKAGE_DIR, BeaconMap, ErrorBody, FrameMeta, LocateResult, load_map

EXAMPLES = PACKAGE_DIR / "examples"
MODEL_OF = {
    "frame.json": FrameMeta,
    "frame_profile_nv21.json": FrameMeta,
    "frame_id.json": FrameMeta,
    "frame_cropped.json": FrameMeta,
    "map.json": BeaconMap,
    "map_shapes.json": BeaconMap,
    "result_ok.json": LocateResult,
    "result_no_fix.json": LocateResult,
    "result_vlc_track.json": LocateResult,
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
        Path("tests/fixtures/bench_1m.json").read_text()
    )
    assert result.ok and golden.ok
    # Loose enough for pipeline tuning, tight enough to catch a changed convention.
    np.testing.assert_allclose(result.position_m, golden.position_m, atol=1e-3)
    np.testing.assert_allclose(result.corners_px, golden.corners_px, atol=0.2)


def test_ok_results_uncertainty_is_a_covariance_and_its_sigmas():
    """position_sigma_m is the square root of the covariance's diagonal; the covariance is symmetric
    positive definite (docs/contract.md, "Uncertainty"); a refusal has neither."""
    golden = LocateResult.model_validate_json((EXAMPLES / "result_ok.json").read_text())
    assert golden.position_sigma_m is not None and golden.position_covariance_m2 is not None
    covariance = np.array(golden.position_covariance_m2)
    np.testing.assert_array_equal(covariance, covariance.T)
    assert np.all(np.linalg.eigvalsh(covariance) > 0)
    np.testing.assert_allclose(golden.position_sigma_m, np.sqrt(np.diag(covariance)), rtol=1e-12)
    # The 95 % ellipse on the floor plan (the XY block times chi-square 2 dof) is millimetres wide here.
    semi_axes = np.sqrt(5.991 * np.linalg.eigvalsh(covariance[:2, :2]))
    assert np.all((semi_axes > 1e-4) & (semi_axes < 1e-2))
    refused = LocateResult.model_validate_json((EXAMPLES / "result_no_fix.json").read_text())
    assert refused.position_sigma_m is None and refused.position_covariance_m2 is None


def test_the_shapes_example_has_each_shape_and_the_doc_names_it():
    shapes = BeaconMap.model_validate_json((EXAMPLES / "map_shapes.json").read_text())
    square, rectangle, circle = shapes.beacons
    assert square.side_m is not None and square.has_corners
    assert rectangle.width_m != rectangle.height_m and rectangle.has_corners
    assert circle.diameter_m is not None and not circle.has_corners
    assert "examples/map_shapes.json" in (PACKAGE_DIR.parent / "docs" / "contract.md").read_text()
