"""A square panel small in the frame (issue 13): when its corners cannot give a fix to the map's
`required_sigma_m`, the outline fit decides, and what that cannot pin down is refused.

The frames are the robustness bench's at 2 m and quarter resolution (an 85 px panel, corner
radius 10 px) through a phone's chain with the ISP off (`simulator.chain.ChainSpec()`); their
indices are ones the corner path handled badly before the fallback: frame 20 gave three
straight sides, frame 64 a fix 5.7 mm off from corners whose own 1-sigma was 14 mm, frame 0 a
fix 62 mm off whose own 1-sigma was 46 mm (its sides are blurred unevenly: `test_motion_blur.py`).
"""

from dataclasses import replace

import numpy as np
import pytest

from server.locator import locate
from shared_schemas import FailureReason
from simulator.benchmarks import AccuracyConfig, accuracy_frame
from simulator.chain import ChainSpec

AT_2M = replace(AccuracyConfig(distance_m=2.0, frames=80, scale=0.25, seed=1), chain=ChainSpec())


def _frame(index: int):
    return accuracy_frame(AT_2M, index)


def _error_mm(result, pose) -> float:
    return 1000 * float(np.hypot(*np.subtract(result.position_m, pose.position_m)[:2]))


def test_three_sides_from_the_polygon_stage_are_located_by_the_outline_instead():
    frame, beacon_map, pose = _frame(20)
    result = locate(frame, beacon_map)
    assert result.ok, result.message
    assert _error_mm(result, pose) < 5.0
    assert any("visible outline of the panel" in w for w in result.warnings)


def test_the_worst_frame_is_no_longer_a_wrong_fix():
    frame, beacon_map, pose = _frame(0)
    result = locate(frame, beacon_map)
    assert result.ok, result.message
    assert _error_mm(result, pose) < 20.0  # before: 62 mm


def test_corners_that_fix_the_position_loosely_give_way_to_the_outline_fit():
    frame, beacon_map, pose = _frame(64)
    result = locate(frame, beacon_map)
    assert result.ok, result.message
    assert _error_mm(result, pose) < 3.0  # the corners alone: 5.7 mm
    assert any("the corners fixed the position only to" in w for w in result.warnings), result.warnings
    # and with the bar above the corners' 14 mm the corner fix stands
    loose = locate(frame, beacon_map.model_copy(update={"required_sigma_m": 0.1}))
    assert loose.ok and not any("the corners fixed" in w for w in loose.warnings)


@pytest.mark.parametrize("index", [0, 2])
def test_a_map_asking_more_than_the_frame_gives_is_refused_not_answered(index):
    frame, beacon_map, _ = _frame(index)
    strict = beacon_map.model_copy(update={"required_sigma_m": 0.0002})  # 0.2 mm from an 85 px panel at 2 m
    result = locate(frame, strict)
    assert not result.ok and result.reason is FailureReason.pose_uncertain, result
    assert "required_sigma_m is 0.2 mm" in result.message
    assert "the position only to" in result.message
