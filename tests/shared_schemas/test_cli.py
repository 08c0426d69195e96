"""shared_schemas.cli's message helpers: pydantic errors in one line, plurals, significant digits."""

import pytest
from pydantic import ValidationError

from shared_schemas import BeaconMap
from shared_schemas.cli import describe_file_error, describe_validation_error, number, plural


def _error(text: str) -> ValidationError:
    with pytest.raises(ValidationError) as caught:
        BeaconMap.model_validate_json(text)
    return caught.value


def test_a_validation_error_is_one_line_naming_the_field_and_the_value():
    error = _error('{"name": "x", "beacons": [{"id": 1, "center_m": [0, 0, 2], "side_m": -1}]}')
    text = describe_validation_error(error, "map.json")
    assert text.startswith("map.json: beacons.0.side_m: Input should be greater than") and text.endswith("(got -1)")
    assert "\n" not in text and "pydantic.dev" not in text and "type=" not in text


def test_more_problems_are_counted_and_bad_json_is_said():
    assert describe_validation_error(_error('{"beacons": []}')).endswith("(and 1 more problem)")
    assert describe_file_error("m.json", _error("{nope")).startswith("m.json: Invalid JSON: ")
    assert describe_file_error("m.json", FileNotFoundError(2, "No such file or directory")) == (
        "m.json: No such file or directory"
    )


@pytest.mark.parametrize(
    ("value", "expected"),
    [(0.0031234, "0.0031"), (0.003, "0.003"), (0.5, "0.50"), (0.123, "0.12"), (12.345, "12.35"), (0.0, "0.00")],
)
def test_small_numbers_keep_their_significant_digits(value, expected):
    assert number(value) == expected


def test_plurals():
    assert [plural(n, "beacon") for n in (0, 1, 2)] == ["0 beacons", "1 beacon", "2 beacons"]
    assert plural(1, "more problem") == "1 more problem" and plural(3, "index", "indices") == "3 indices"
