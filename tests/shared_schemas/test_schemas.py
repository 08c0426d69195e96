"""The exported JSON Schemas are current; bundled profiles and maps load and validate."""

import pytest
from pydantic import ValidationError

from shared_schemas import BeaconMap, device_profiles, load_map
from shared_schemas.export import SCHEMA_DIR, rendered_schemas


def test_exported_schemas_are_current():
    for name, text in rendered_schemas().items():
        path = SCHEMA_DIR / name
        assert path.exists() and path.read_text() == text, (
            f"{path} is stale: run `python -m shared_schemas.export`")


def test_bundled_profiles_and_demo_map_load():
    assert {"xiaomi-mi8-front", "xiaomi-mi8-rear"} <= set(device_profiles())
    assert load_map().beacons[0].side_m == 0.174


def test_map_rejects_duplicate_ids_and_impossible_radius():
    beacon = {"id": 1, "center_m": [0, 0, 2.7], "side_m": 0.174}
    with pytest.raises(ValidationError, match="unique"):
        BeaconMap.model_validate({"name": "x", "beacons": [beacon, beacon]})
    with pytest.raises(ValidationError, match="half of the panel.s shorter side"):
        BeaconMap.model_validate({"name": "x", "beacons": [{**beacon, "corner_radius_m": 0.1}]})
