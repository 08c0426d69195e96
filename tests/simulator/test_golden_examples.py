"""The capture protocol's golden examples are what a rendered capture gives today (simulator/golden_examples.py)."""

import json
import math

import pytest

from server.ingest import LumaFrame
from server.vlc.capture import id_frame_problem
from shared_schemas import FrameKind, FrameMeta, LocateResult
from simulator.golden_examples import EXAMPLES_DIR, rendered_examples

REGENERATE = "run `python -m simulator.golden_examples`"


def differences(golden, fresh, path="") -> list[str]:
    """Where `fresh` differs from `golden`: floats to 1e-6 (relative), timings by their stages only."""
    if isinstance(golden, dict) and isinstance(fresh, dict):
        if golden.keys() != fresh.keys():
            return [f"{path}: keys {sorted(golden)} != {sorted(fresh)}"]
        if path.endswith("timing_ms"):
            return []
        return [d for key in golden for d in differences(golden[key], fresh[key], f"{path}.{key}")]
    if isinstance(golden, list) and isinstance(fresh, list) and len(golden) == len(fresh):
        return [d for i, (g, f) in enumerate(zip(golden, fresh)) for d in differences(g, f, f"{path}[{i}]")]
    if isinstance(golden, float) and isinstance(fresh, (int, float)) and not isinstance(fresh, bool):
        return [] if math.isclose(golden, fresh, rel_tol=1e-6, abs_tol=1e-9) else [f"{path}: {golden} != {fresh}"]
    return [] if golden == fresh else [f"{path}: {golden!r} != {fresh!r}"]


@pytest.fixture(scope="module")
def fresh():
    return rendered_examples()


def test_the_capture_examples_are_current(fresh):
    for name, data in fresh.items():
        golden = json.loads((EXAMPLES_DIR / name).read_text())
        assert not differences(golden, data), f"{name} is stale ({differences(golden, data)[:3]}): {REGENERATE}"


def test_the_differences_catch_a_changed_value_and_ignore_timings():
    golden = {"a": [1.0, 2.0], "timing_ms": {"total": 3.0}}
    assert not differences(golden, {"a": [1.0, 2.0000000001], "timing_ms": {"total": 9.0}})
    assert differences(golden, {"a": [1.0, 2.1], "timing_ms": {"total": 3.0}})
    assert differences(golden, {"a": [1.0, 2.0], "timing_ms": {"roi": 3.0}})


def test_the_examples_say_what_they_claim(fresh):
    id_meta = FrameMeta.model_validate(fresh["frame_id.json"])
    assert id_meta.frame_kind is FrameKind.id
    assert id_frame_problem(LumaFrame(None, id_meta, id_meta.camera)) is None  # the server reads it
    cropped = FrameMeta.model_validate(fresh["frame_cropped.json"])
    assert cropped.crop is not None and cropped.width < cropped.crop.full_width
    result = LocateResult.model_validate(fresh["result_vlc_track.json"])
    assert result.ok and result.vlc is not None and result.vlc.confident and result.vlc.beacon_id == result.beacon_id
    assert result.track is not None and result.beacons_in_view and result.ambiguity_ratio is not None
    assert len(result.corners_px) == 4 and "total" in result.timing_ms
    # corners in the window's pixels (docs/contract.md, "Crop")
    assert all(0 <= x < cropped.width and 0 <= y < cropped.height for x, y in result.corners_px)
