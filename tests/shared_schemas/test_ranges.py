"""Every number of the contract has a physical range: a number outside it is refused by the model,
naming the field, and the bounds are in the exported JSON Schemas (docs/contract.md, "Ranges")."""

import copy
import json

import pytest
from pydantic import ValidationError

from shared_schemas import PACKAGE_DIR, BeaconMap, DeviceProfile, FrameMeta, device_profiles, models
from shared_schemas.export import SCHEMA_DIR

EXAMPLES = PACKAGE_DIR / "examples"
FRAME = json.loads((EXAMPLES / "frame.json").read_text())
PROFILE_FRAME = json.loads((EXAMPLES / "frame_profile_nv21.json").read_text())
MAP = json.loads((EXAMPLES / "map.json").read_text())
PROFILE = device_profiles()["xiaomi-mi8-rear"].model_dump()


def _changed(document: dict, dotted: str, value) -> dict:
    changed = copy.deepcopy(document)
    target, *path = changed, *dotted.split(".")
    for key in path[:-1]:
        target = target[int(key)] if isinstance(target, list) else target[key]
    target[int(path[-1]) if isinstance(target, list) else path[-1]] = value
    return changed


def _refused_field(model, document: dict) -> str:
    with pytest.raises(ValidationError) as error:
        model.model_validate(document)
    location = error.value.errors()[0]["loc"]
    return ".".join(str(p) for p in location if not str(p).startswith(("CameraIntrinsics", "ProfileRef")))


# (field changed, value, the field the error names): the reliability probe's numbers first
BAD_FRAMES = [
    ("camera.fx", 1e308, "camera.fx"),
    ("camera.fx", 1e-300, "camera.fx"),
    ("camera.fy", 0.5, "camera.fy"),
    ("camera.fy", 2e6, "camera.fy"),
    ("camera.cx", 1e308, "camera.cx"),
    ("camera.cx", -1e308, "camera.cx"),
    ("camera.cy", 1e10, "camera.cy"),
    ("camera.cx", 3 * 970.0, "camera.cx"),  # within the absolute bound, but two widths beyond the frame
    ("camera.cy", -1297.0, "camera.cy"),
    ("camera.distortion", [1e300, 0, 0, 0, 0], "camera.distortion.0"),
    ("camera.distortion", [1e10] * 8, "camera.distortion.0"),
    ("camera.distortion", [0, 0, 0, 1000.5], "camera.distortion.3"),
    ("camera.pixel_size_m", 1e-300, "camera.pixel_size_m"),
    ("camera.pixel_size_m", 1.0, "camera.pixel_size_m"),
    ("camera.focal_length_m", 1e-300, "camera.focal_length_m"),
    ("camera.focal_length_m", 10.0, "camera.focal_length_m"),
    ("gravity_camera", [1e200, 1e200, 1e200], "gravity_camera.0"),
    ("gravity_camera", [0.0, 0.0, -101.0], "gravity_camera.2"),
    ("gravity_camera", [1e-300, 1e-300, 1e-300], "gravity_camera"),  # in range, but no direction
    ("timestamp_ns", 10**400, "timestamp_ns"),
    ("timestamp_ns", 2**63, "timestamp_ns"),
    ("timestamp_ns", -1, "timestamp_ns"),
    ("width", 10**400, "width"),
    ("width", 100_001, "width"),
    ("height", 0, "height"),
    ("row_stride", 200_001, "row_stride"),
    ("exposure_s", 1e-300, "exposure_s"),
    ("exposure_s", 1e6, "exposure_s"),
    ("iso", 1e-300, "iso"),
    ("iso", 1e300, "iso"),
    ("rolling_shutter_skew_s", 2.0, "rolling_shutter_skew_s"),
    ("heading_deg", 1e300, "heading_deg"),
    ("heading_deg", -361.0, "heading_deg"),
    ("ground_truth.position_m", [1e300, 0.0, 0.0], "ground_truth.position_m.0"),
    ("ground_truth.rotation_wc.1", [0.0, 1e300, 0.0], "ground_truth.rotation_wc.1.1"),
    ("crop", {"x": -1, "y": 0, "full_width": 970, "full_height": 1296}, "crop.x"),
    ("crop", {"x": 0, "y": 10**400, "full_width": 970, "full_height": 1296}, "crop.y"),
    ("crop", {"x": 0, "y": 0, "full_width": 10**400, "full_height": 1296}, "crop.full_width"),
    ("crop", {"x": 0, "y": 0, "full_width": 970, "full_height": 0}, "crop.full_height"),
    ("crop", {"x": 1, "y": 0, "full_width": 970, "full_height": 1296}, "crop"),  # the window does not fit
]


@pytest.mark.parametrize("dotted, value, field", BAD_FRAMES, ids=[f"{f}={str(v)[:24]}" for f, v, _ in BAD_FRAMES])
def test_frame_numbers_out_of_range_are_refused_naming_the_field(dotted, value, field):
    assert _refused_field(FrameMeta, _changed(FRAME, dotted, value)) == field


BAD_BEACONS = [
    ("side_m", 1e-300, "beacons.0.side_m"),
    ("side_m", 1e308, "beacons.0.side_m"),
    ("side_m", 0.004, "beacons.0.side_m"),
    ("side_m", 10.5, "beacons.0.side_m"),
    ("center_m", [0.0, 0.0, 1e308], "beacons.0.center_m.2"),
    ("center_m", [-1.1e7, 0.0, 0.0], "beacons.0.center_m.0"),
    ("yaw_deg", 1e300, "beacons.0.yaw_deg"),
    ("corner_radius_m", 1e300, "beacons.0.corner_radius_m"),
    ("id", 256, "beacons.0.id"),
]


@pytest.mark.parametrize("key, value, field", BAD_BEACONS, ids=[f"{k}={v}" for k, v, _ in BAD_BEACONS])
def test_map_numbers_out_of_range_are_refused_naming_the_field(key, value, field):
    assert _refused_field(BeaconMap, _changed(MAP, f"beacons.0.{key}", value)) == field


SHAPES_MAP = json.loads((EXAMPLES / "map_shapes.json").read_text())
BAD_SHAPED_BEACONS = [  # beacon 1 is a rectangle, beacon 2 a circle
    ("beacons.1.width_m", 1e-300),
    ("beacons.1.width_m", 10.5),
    ("beacons.1.height_m", 0.004),
    ("beacons.1.height_m", 1e308),
    ("beacons.2.diameter_m", 0.004),
    ("beacons.2.diameter_m", 1e308),
]


@pytest.mark.parametrize("dotted, value", BAD_SHAPED_BEACONS, ids=[f"{d}={v}" for d, v in BAD_SHAPED_BEACONS])
def test_shaped_beacons_sizes_out_of_range_are_refused_naming_the_field(dotted, value):
    assert _refused_field(BeaconMap, _changed(SHAPES_MAP, dotted, value)) == dotted


BAD_PROFILES = [
    ("pixel_size_m", 1e-300),
    ("focal_length_m", 1e308),
    ("width", 10**400),
    ("height", 0),
    ("distortion", [1e300, 0, 0, 0, 0]),
    ("distortion", [0.1, 0.1, 0.0]),  # not an OpenCV length
    ("gravity_sigma_deg", 1e300),
]


@pytest.mark.parametrize("key, value", BAD_PROFILES, ids=[f"{k}={str(v)[:16]}" for k, v in BAD_PROFILES])
def test_profile_numbers_out_of_range_are_refused_naming_the_field(key, value):
    assert _refused_field(DeviceProfile, {**PROFILE, key: value}).split(".")[0] == key


EDGES_OF_THE_RANGES = [
    ("camera.fx", 1.0),
    ("camera.fx", 1e6),
    ("camera.cx", -970.0),
    ("camera.cx", 1940.0),
    ("camera.cy", 1e-300),
    ("camera.distortion", [1000.0, -1000.0, 1000.0, -1000.0, 1000.0, -1000.0, 1000.0, -1000.0]),
    ("gravity_camera", [100.0, -100.0, 100.0]),
    ("gravity_camera", [0.0, 0.0, 1e-6]),
    ("timestamp_ns", 2**63 - 1),
    ("timestamp_ns", 0),
    ("exposure_s", 1e-9),
    ("rolling_shutter_skew_s", 0.0),
    ("heading_deg", -360.0),
    ("width", 100_000),
]


@pytest.mark.parametrize("dotted, value", EDGES_OF_THE_RANGES, ids=[f"{f}={v}"[:40] for f, v in EDGES_OF_THE_RANGES])
def test_the_ends_of_the_ranges_are_accepted(dotted, value):
    document = _changed(FRAME, dotted, value)
    if dotted == "width":
        document.update(row_stride=value, camera={**document["camera"], "cx": 5000.0})
    FrameMeta.model_validate(document)


def test_a_cropped_frames_principal_point_is_checked_against_the_full_frame():
    """The camera describes the full frame (server/camera.py resolve_camera moves cx by the crop)."""
    window = {**FRAME, "width": 100, "height": 100, "row_stride": 100}
    crop = {"x": 2000, "y": 3000, "full_width": 3024, "full_height": 4032}
    meta = FrameMeta.model_validate({**window, "camera": {**FRAME["camera"], "cx": 1511.5, "cy": 2015.5}, "crop": crop})
    assert meta.camera.cx == 1511.5  # 15 window widths away from the window: fine, it is the full frame's centre
    bad = {**window, "camera": {**FRAME["camera"], "cx": 6049.0, "cy": 2015.5}, "crop": crop}
    assert _refused_field(FrameMeta, bad) == "camera.cx"


def test_gravity_of_a_sensor_in_metres_per_second_squared_is_normalised():
    meta = FrameMeta.model_validate(_changed(FRAME, "gravity_camera", [0.0, 0.0, -9.81]))
    assert meta.gravity_camera == [0.0, 0.0, -1.0]


def test_the_golden_examples_and_bundled_files_are_within_the_ranges():
    FrameMeta.model_validate(FRAME)
    FrameMeta.model_validate(PROFILE_FRAME)
    BeaconMap.model_validate(MAP)
    BeaconMap.model_validate(SHAPES_MAP)
    assert device_profiles()


def _bounds(prop: dict) -> tuple:
    branch = next(b for b in prop.get("anyOf", [prop]) if b.get("type") != "null")
    while "items" in branch:
        branch = branch["items"]
    return tuple(branch.get(k) for k in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"))


def test_the_exported_schemas_carry_the_bounds():
    frame = json.loads((SCHEMA_DIR / "frame.schema.json").read_text())
    camera = frame["$defs"]["CameraIntrinsics"]["properties"]
    assert _bounds(camera["fx"]) == (models.MIN_FOCAL_PX, None, models.MAX_FOCAL_PX, None)
    assert _bounds(camera["distortion"]) == (-models.MAX_DISTORTION, None, models.MAX_DISTORTION, None)
    assert _bounds(frame["properties"]["timestamp_ns"]) == (0, None, None, 2**63)
    assert _bounds(frame["properties"]["gravity_camera"]) == (-models.MAX_GRAVITY, None, models.MAX_GRAVITY, None)
    beacon = json.loads((SCHEMA_DIR / "map.schema.json").read_text())["$defs"]["Beacon"]["properties"]
    openapi = json.loads((PACKAGE_DIR / "openapi.json").read_text())["components"]["schemas"]
    for size in ("side_m", "width_m", "height_m", "diameter_m"):
        assert _bounds(beacon[size]) == (models.MIN_SIDE_M, None, models.MAX_SIDE_M, None), size
        assert _bounds(openapi["Beacon"]["properties"][size]) == (models.MIN_SIDE_M, None, models.MAX_SIDE_M, None)
