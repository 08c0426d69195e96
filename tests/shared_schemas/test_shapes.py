"""Panel shapes (docs/contract.md, "Panel shapes"): a rounded rectangle gives `side_m` (a square)
or `width_m` and `height_m`; a circle gives `diameter_m` only and no corner radius. Any other
combination is refused with a message naming the fields, and a map of squares written before
shapes existed reads and stores unchanged but for the added default `shape`."""

import json

import pytest
from pydantic import ValidationError

from server.store import MapStore
from shared_schemas import DEMO_MAP_PATH, PACKAGE_DIR, Beacon, BeaconMap, PanelShape

EXAMPLES = PACKAGE_DIR / "examples"
CENTRE = {"id": 1, "center_m": [0.0, 0.0, 2.7]}


def _refusal(beacon: dict) -> str:
    """The message of the one error refusing `beacon`, inside a map, and where it points."""
    with pytest.raises(ValidationError) as error:
        BeaconMap.model_validate({"name": "x", "beacons": [beacon]})
    (only,) = error.value.errors()
    assert only["loc"][:2] == ("beacons", 0)
    return only["msg"]


def test_a_square_is_the_default_shape_and_gives_side_m():
    beacon = Beacon.model_validate({**CENTRE, "side_m": 0.174, "corner_radius_m": 0.02})
    assert beacon.shape is PanelShape.rounded_rectangle and beacon.has_corners
    assert beacon.extent_m == (0.174, 0.174) and beacon.size_m == 0.174
    assert beacon.outline_radius_m == 0.02


def test_a_rectangle_gives_width_along_x_b_and_height_along_y_b():
    beacon = Beacon.model_validate(
        {**CENTRE, "shape": "rounded_rectangle", "width_m": 1.195, "height_m": 0.295, "corner_radius_m": 0.01}
    )
    assert beacon.extent_m == (1.195, 0.295) and beacon.size_m == 1.195 and beacon.has_corners
    assert beacon.side_m is None
    # The shape may be left out: a rounded rectangle is the default.
    assert Beacon.model_validate({**CENTRE, "width_m": 0.3, "height_m": 0.6}).extent_m == (0.3, 0.6)


def test_a_rectangles_corner_radius_is_below_half_of_its_shorter_side():
    Beacon.model_validate({**CENTRE, "width_m": 1.2, "height_m": 0.3, "corner_radius_m": 0.149})
    message = _refusal({**CENTRE, "width_m": 1.2, "height_m": 0.3, "corner_radius_m": 0.15})
    assert "corner_radius_m" in message and "shorter side" in message


def test_a_circle_gives_its_diameter_only():
    beacon = Beacon.model_validate({**CENTRE, "shape": "circle", "diameter_m": 0.2})
    assert beacon.shape is PanelShape.circle and not beacon.has_corners
    assert beacon.extent_m == (0.2, 0.2) and beacon.size_m == 0.2
    assert beacon.outline_radius_m == 0.1  # all arc
    no_radius = Beacon.model_validate({**CENTRE, "shape": "circle", "diameter_m": 0.2, "corner_radius_m": 0})
    assert not no_radius.has_corners and no_radius.outline_radius_m == 0.1


@pytest.mark.parametrize(
    "sizes, named",
    [
        ({}, []),
        ({"side_m": 0.2, "width_m": 0.2, "height_m": 0.3}, ["height_m", "side_m", "width_m"]),
        ({"side_m": 0.2, "width_m": 0.3}, ["side_m", "width_m"]),
        ({"width_m": 0.3}, ["width_m"]),
        ({"height_m": 0.3}, ["height_m"]),
        ({"diameter_m": 0.2}, ["diameter_m"]),
        ({"side_m": 0.2, "diameter_m": 0.2}, ["diameter_m", "side_m"]),
    ],
    ids=lambda value: "+".join(value) if isinstance(value, dict) else None,
)
def test_a_rounded_rectangle_with_other_sizes_is_refused_naming_them(sizes, named):
    message = _refusal({**CENTRE, **sizes})
    assert "a rounded rectangle has side_m, or width_m and height_m" in message
    assert f"got {named}" in message


@pytest.mark.parametrize(
    "sizes, named",
    [
        ({}, []),
        ({"side_m": 0.2}, ["side_m"]),
        ({"diameter_m": 0.2, "side_m": 0.2}, ["diameter_m", "side_m"]),
        ({"width_m": 0.2, "height_m": 0.2}, ["height_m", "width_m"]),
        ({"diameter_m": 0.2, "width_m": 0.2, "height_m": 0.2}, ["diameter_m", "height_m", "width_m"]),
    ],
    ids=lambda value: "+".join(value) if isinstance(value, dict) else None,
)
def test_a_circle_with_other_sizes_is_refused_naming_them(sizes, named):
    message = _refusal({**CENTRE, "shape": "circle", **sizes})
    assert f"a circle has diameter_m and no other size, got {named}" in message


def test_a_circle_with_a_corner_radius_is_refused():
    assert "a circle has no corner_radius_m" in _refusal(
        {**CENTRE, "shape": "circle", "diameter_m": 0.2, "corner_radius_m": 0.02}
    )


def test_an_unknown_shape_is_refused_naming_the_field():
    with pytest.raises(ValidationError) as error:
        BeaconMap.model_validate({"name": "x", "beacons": [{**CENTRE, "shape": "hexagon", "side_m": 0.2}]})
    assert error.value.errors()[0]["loc"] == ("beacons", 0, "shape")


@pytest.mark.parametrize("field", ["width_m", "height_m", "diameter_m"])
@pytest.mark.parametrize("value", [0.004, 10.5, 1e-300, 1e308])
def test_every_size_has_the_sides_range(field, value):
    sizes = {"diameter_m": 0.2} if field == "diameter_m" else {"width_m": 0.3, "height_m": 0.6}
    beacon = {**CENTRE, "shape": "circle" if field == "diameter_m" else "rounded_rectangle", **sizes, field: value}
    with pytest.raises(ValidationError) as error:
        BeaconMap.model_validate({"name": "x", "beacons": [beacon]})
    assert error.value.errors()[0]["loc"] == ("beacons", 0, field)


@pytest.mark.parametrize("path", [EXAMPLES / "map.json", DEMO_MAP_PATH], ids=lambda path: path.name)
def test_a_stored_map_of_squares_is_unchanged_but_for_the_default_shape(tmp_path, path):
    """What `PUT /v1/maps/{name}` writes (server/store.py) for a map written before shapes existed."""
    original = json.loads(path.read_text())
    assert all("shape" not in beacon for beacon in original["beacons"])
    store = MapStore(tmp_path)
    store.put(original["name"], BeaconMap.model_validate(original))
    stored = json.loads((tmp_path / "maps" / f"{original['name']}.json").read_text())
    beacons = [{**b, "shape": "rounded_rectangle"} for b in original["beacons"]]
    expected = {**original, "beacons": beacons, "required_sigma_m": 0.01}  # and the map's default need
    assert stored == expected
    assert store.get(original["name"]) == BeaconMap.model_validate(original)


def test_a_stored_map_of_shapes_is_unchanged(tmp_path):
    original = json.loads((EXAMPLES / "map_shapes.json").read_text())
    shapes = BeaconMap.model_validate(original)
    assert [b.shape for b in shapes.beacons] == [PanelShape.rounded_rectangle] * 2 + [PanelShape.circle]
    assert [b.extent_m for b in shapes.beacons] == [(0.174, 0.174), (1.195, 0.295), (0.2, 0.2)]
    MapStore(tmp_path).put(original["name"], shapes)
    stored = json.loads((tmp_path / "maps" / f"{original['name']}.json").read_text())
    original["beacons"][0]["shape"] = "rounded_rectangle"  # the square left it to the default
    original["beacons"][2]["yaw_deg"] = 0.0  # and the circle its yaw
    original["beacons"][2]["corner_radius_m"] = 0.0
    assert stored == original
