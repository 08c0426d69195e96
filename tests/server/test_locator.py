"""The entry point never raises on a readable frame: numbers at the ends of the contract's ranges
give a fix or a refusal, and a numerical failure of a stage is a `numerical_failure` refusal that
names the stage and is logged with its traceback; bad input (`FrameError`) still raises."""

import copy
import json
import logging
from pathlib import Path

import cv2
import numpy as np
import pytest

import server.pipeline
from server.camera import resolve_camera
from server.ingest import LumaFrame, parse_meta, read_fixture
from server.locator import locate
from server.options import LocateOptions
from server.outcomes import FrameError
from server.pipeline import PipelineOptions
from server.pose.solve import GravityMode
from server.tracking.devices import Devices
from shared_schemas import BeaconMap, FailureReason, LocateResult, load_map

FIXTURE = read_fixture(Path(__file__).parents[1] / "fixtures" / "bench_1m.json")
META = json.loads(FIXTURE.meta.model_dump_json(by_alias=True, exclude_none=True))
ONE = load_map()
PANEL = ONE.beacons[0]
TWO = BeaconMap(name="two", beacons=[PANEL, PANEL.model_copy(update={"id": PANEL.id + 1, "center_m": [5.0, 0.0, 1.0]})])
ALWAYS = LocateOptions(pipeline=PipelineOptions(gravity_mode=GravityMode.always))


def frame_with(**changes) -> LumaFrame:
    """The fixture's pixels with its metadata changed (`camera__fx=...`), validated as an upload's."""
    data = copy.deepcopy(META)
    for dotted, value in changes.items():
        target, *path = data, *dotted.split("__")
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    meta = parse_meta(data)
    return LumaFrame(FIXTURE.pixels, meta, resolve_camera(meta))


EXTREME_FRAMES = {
    "fx = fy = 1": dict(camera__fx=1.0, camera__fy=1.0),
    "fx = fy = 1e6": dict(camera__fx=1e6, camera__fy=1e6),
    "fx = 1e6, fy = 1": dict(camera__fx=1e6, camera__fy=1.0),
    "principal point at the corner": dict(camera__cx=1e-300, camera__cy=1e-300),
    "principal point a frame beyond": dict(camera__cx=-970.0, camera__cy=2592.0),
    "distortion all +1000": dict(camera__distortion=[1000.0] * 8),
    "distortion all -1000": dict(camera__distortion=[-1000.0] * 8),
    "k1 = 1000": dict(camera__distortion=[1000.0, 0.0, 0.0, 0.0, 0.0]),
    "p1 = p2 = 1000": dict(camera__distortion=[0.0, 0.0, 1000.0, 1000.0]),
    "k6 = 1000": dict(camera__distortion=[0.0] * 7 + [1000.0]),
    "fx = 1 and distortion": dict(camera__fx=1.0, camera__fy=1.0, camera__distortion=[1000.0] * 8),
    "gravity 100 each": dict(gravity_camera=[100.0, 100.0, 100.0]),
    "gravity barely nonzero": dict(gravity_camera=[1e-6, 0.0, 0.0]),
    "last timestamp": dict(timestamp_ns=2**63 - 1),
    "heading a turn": dict(heading_deg=-360.0),
    "ID frame, last timestamp, shortest exposure": dict(
        frame_kind="id", timestamp_ns=2**63 - 1, exposure_s=1e-9, rolling_shutter_skew_s=1.0
    ),
    "ID frame, skew 5e-324": dict(frame_kind="id", timestamp_ns=0, exposure_s=1e-4, rolling_shutter_skew_s=5e-324),
}


@pytest.mark.parametrize("name", EXTREME_FRAMES)
def test_numbers_at_the_ends_of_their_ranges_give_a_result_on_every_path(name):
    frame = frame_with(**EXTREME_FRAMES[name])
    devices = Devices()
    for beacon_map, options, device in [
        (ONE, LocateOptions(), None),
        (ONE, ALWAYS, None),
        (TWO, LocateOptions(), None),
        (TWO, ALWAYS, "phone"),
    ]:
        result = locate(frame, beacon_map, options, device_id=device, devices=devices)
        assert isinstance(result, LocateResult)
        assert result.ok or result.reason is not None, result


EXTREME_MAPS = {
    "side 5 mm": {"side_m": 0.005, "corner_radius_m": 0.0},
    "side 10 m": {"side_m": 10.0, "corner_radius_m": 4.99},
    "centre 1e7 m away": {"center_m": [1e7, -1e7, 1e7]},
    "yaw a turn": {"yaw_deg": 360.0},
}


@pytest.mark.parametrize("name", EXTREME_MAPS)
def test_maps_at_the_ends_of_their_ranges_give_a_result(name):
    beacon_map = BeaconMap.model_validate({"name": "edge", "beacons": [{**PANEL.model_dump(), **EXTREME_MAPS[name]}]})
    for frame in (FIXTURE, frame_with(camera__distortion=[1000.0] * 8)):
        result = locate(frame, beacon_map, ALWAYS)
        assert result.ok or result.reason is not None, result


def _raise(error: BaseException):
    def stage(*args, **kwargs):
        raise error

    return stage


@pytest.mark.parametrize(
    "error",
    [cv2.error("(-215:Assertion failed) s_(0) >= 1e-7"), np.linalg.LinAlgError("Singular matrix"),
     OverflowError("int too large to convert to float"), FloatingPointError("overflow"), ZeroDivisionError("div")],
    ids=lambda error: type(error).__name__,
)
def test_a_stage_that_fails_numerically_gives_a_refusal_naming_it(monkeypatch, caplog, error):
    monkeypatch.setattr(server.pipeline, "solve_pose", _raise(error))
    with caplog.at_level(logging.WARNING, logger="lumipose.pipeline"):
        result = locate(FIXTURE, ONE)
    assert not result.ok and result.reason is FailureReason.numerical_failure
    assert "in server.pipeline._corner_pose:" in result.message and str(error.args[0]) in result.message
    record = next(r for r in caplog.records if r.name == "lumipose.pipeline")
    assert record.levelno == logging.WARNING and record.exc_info and record.exc_info[1] is error


def test_a_numerical_failure_in_a_device_session_leaves_the_device_usable(monkeypatch):
    devices = Devices()
    with monkeypatch.context() as patch:
        patch.setattr(server.pipeline, "solve_pose", _raise(cv2.error("boom")))
        assert locate(FIXTURE, TWO, beacon_id=None, device_id="phone", devices=devices).reason in (
            FailureReason.numerical_failure,
            FailureReason.unknown_beacon,  # no ID frames: the session may not reach the pose
        )
    assert isinstance(locate(FIXTURE, TWO, device_id="phone", devices=devices), LocateResult)
    assert locate(FIXTURE, ONE).ok


def test_a_pose_that_is_not_finite_is_refused_before_it_reaches_a_result(monkeypatch):
    real = server.pipeline.solve_pose

    def nan_pose(*args, **kwargs):
        pose = real(*args, **kwargs)
        return type(pose)(**{**vars(pose), "position_m": np.full(3, np.nan)})

    monkeypatch.setattr(server.pipeline, "solve_pose", nan_pose)
    result = locate(FIXTURE, ONE)
    assert not result.ok and result.reason is FailureReason.numerical_failure
    assert "not finite" in result.message and "pose" in result.timing_ms


def test_bad_input_still_raises_a_frame_error(monkeypatch):
    monkeypatch.setattr(server.pipeline, "solve_pose", _raise(FrameError("no such thing", field="camera")))
    with pytest.raises(FrameError):
        locate(FIXTURE, ONE)


@pytest.mark.parametrize("error", [ValueError("too many values to unpack"), KeyError("x")], ids=lambda e: type(e).__name__)
def test_a_plain_bug_in_a_stage_is_not_passed_off_as_a_numerical_failure(monkeypatch, error):
    monkeypatch.setattr(server.pipeline, "solve_pose", _raise(error))
    with pytest.raises(type(error)):
        locate(FIXTURE, ONE)


def test_the_options_for_a_map_are_made_once_for_the_same_objects_and_anew_for_others():
    from server.locator import _OptionsForMap

    made, options, beacon_map = _OptionsForMap(keep=2), LocateOptions(), load_map()
    first = made.options(options, beacon_map)
    assert first == options.for_map(beacon_map) and made.options(options, beacon_map) is first
    strict = beacon_map.model_copy(update={"required_sigma_m": 0.001})  # another object: its own options
    assert made.options(options, strict).pipeline.outline_fit.max_sigma_m == 0.001
    assert made.options(LocateOptions(), beacon_map) is not first  # equal options, another object
    assert made.options(options, beacon_map) is not first  # the first pair was dropped: two kept


def test_a_requests_own_options_take_no_place_among_the_kept_ones():
    from dataclasses import replace

    from server.diagnostics import Diagnostics
    from server.locator import _OptionsForMap

    made, options, beacon_map = _OptionsForMap(keep=2), LocateOptions(), load_map()
    first = made.options(options, beacon_map)
    for _ in range(3):  # annotated requests, each with its own diagnostics
        watched = replace(options, pipeline=replace(options.pipeline, diagnostics=Diagnostics()))
        assert made.options(watched, beacon_map).pipeline.diagnostics is watched.pipeline.diagnostics
    assert made.options(options, beacon_map) is first  # still kept
