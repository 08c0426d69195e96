"""The device session on the first captures of the office zig-zag (rendered, fixed seed)."""

import numpy as np

from simulator.bench_office import OfficeConfig, run_walk


def test_a_walk_starting_between_panels_gets_fixes_with_right_ids():
    # the zig-zag starts on the area's border, where every panel is cut off by the frame edge
    report = run_walk(OfficeConfig(walk="zigzag", max_captures=6, pose_scale=0.5, seed=2))
    records = report["records"]
    ok = [r for r in records if r["ok"]]
    assert len(ok) >= 4, [r.get("reason") for r in records]
    assert all(r["beacon_id"] == r["true_beacon"] for r in ok)
    assert all(r["source"] in ("vlc", "track") for r in ok)
    # half-resolution pose frames, as in the bench
    assert np.mean([r["error_mm"] for r in ok]) < 10.0
    # raw fix and filtered track are both kept
    assert all("filtered_m" in r for r in ok)
