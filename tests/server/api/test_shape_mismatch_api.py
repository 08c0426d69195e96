"""A real server refuses a fix its own evidence does not bear out (issue 27): `shape_mismatch`, as a result."""

import pytest

from lumipose_client import read_fixture_files
from tests.helpers import PANEL, PANEL_WRONG_RADIUS, TWO_SHAPES, render_panel_frame


@pytest.fixture(scope="module")
def panel_frame(tmp_path_factory):
    return read_fixture_files(render_panel_frame(tmp_path_factory.mktemp("panel")))


def test_wrong_maps_are_refused_and_the_right_one_fixes(client, panel_frame):
    meta, data = panel_frame
    for beacon_map in (PANEL, PANEL_WRONG_RADIUS, TWO_SHAPES):
        client.put_map(beacon_map)
    try:
        fixed = client.locate(data, meta, map="panel")
        assert fixed.ok and abs(fixed.position_m[0] - 0.1) < 1e-3 and abs(fixed.position_m[1] - 0.2) < 1e-3
        assert client.locate(data, meta, map="two-shapes", beacon_id=1).ok
        for options, beacon in (
            ({"map": "panel-r05"}, "map beacon 1's shape (0.6 m, corner radius 0.05 m)"),
            ({}, "map beacon 0's shape (0.174 m, corner radius 0.02 m)"),  # the active map: the test bench
            ({"map": "two-shapes", "beacon_id": 2}, "map beacon 2's shape (0.3 m, corner radius 0.03 m)"),
        ):
            result = client.locate(data, meta, **options)
            assert not result.ok and result.reason.value == "shape_mismatch", (options, result)
            assert beacon in result.message and "degrees of freedom" in result.message
    finally:
        for beacon_map in (PANEL, PANEL_WRONG_RADIUS, TWO_SHAPES):
            client.delete_map(beacon_map.name)
