"""The compiled sub-pixel kernels are their NumPy references: the whole stage on the benches'
frames (accuracy at full and quarter resolution, a square of bench shapes; bench partial's cut
panels take the outline path, not this stage), and the pieces where the frames do not reach
(NumPy's sums of a row, OpenCV's LU, a fit whose equations are singular)."""

from dataclasses import replace

import cv2
import numpy as np
import pytest

import server.pipeline as pipeline
from server.locator import locate
from server.options import LocateOptions
from server.vision import subpixel_kernel
from server.vision.subpixel import EdgeRules, _fit_lines, _profile_layout, profile_offsets, refine_edges
from simulator.bench_shapes import ShapesConfig, shape_frame
from simulator.benchmarks import AccuracyConfig, accuracy_frame


def stage_calls(monkeypatch) -> list[tuple]:
    """`refine_edges`' arguments as the pipeline gives them on a few of the benches' frames."""
    calls = []

    def recorded(*args):
        calls.append(args)
        return refine_edges(*args)

    monkeypatch.setattr(pipeline, "refine_edges", recorded)
    for scale, distance_m in [(1.0, 1.0), (0.25, 1.0), (0.25, 2.0), (0.25, 3.0)]:
        frame, beacon_map, _ = accuracy_frame(AccuracyConfig(distance_m=distance_m, seed=1, scale=scale), 0)
        locate(frame, beacon_map, LocateOptions())
    square = shape_frame(ShapesConfig(scale=0.25), "square-174", 0)
    locate(square.frame, square.beacon_map, square.options)
    return calls


def test_the_compiled_stage_is_the_numpy_stage_on_bench_frames(monkeypatch):
    calls = stage_calls(monkeypatch)
    assert len(calls) == 5
    for args in calls:
        rules = args[7] if len(args) > 7 else EdgeRules()
        assert rules.compiled
        compiled = refine_edges(*args[:7], rules)
        reference = refine_edges(*args[:7], replace(rules, compiled=False))
        np.testing.assert_allclose(compiled.corners, reference.corners, rtol=0, atol=1e-12)
        np.testing.assert_allclose(compiled.lines, reference.lines, rtol=0, atol=1e-12)
        for name in ("edge_shift_px", "line_rms_px", "line_sigma_px", "curvature_px", "uneven_px", "locking_px"):
            assert getattr(compiled, name) == pytest.approx(getattr(reference, name), rel=1e-12, abs=1e-15)
        offsets = profile_offsets(rules.half_window_px, rules.step_px)
        layouts = [
            _profile_layout(args[2], args[4], offsets, args[0].shape, replace(rules, compiled=on)) for on in (1, 0)
        ]
        for made, expected in zip(*layouts, strict=True):  # where the profiles are sampled: the very same
            assert np.array_equal(made, expected)
        assert (compiled.points_per_side, compiled.arc_points, compiled.warnings) == (
            reference.points_per_side,
            reference.arc_points,
            reference.warnings,
        )


def test_sums_are_numpys_sums_of_a_row():
    rng = np.random.default_rng(3)
    for count in range(0, subpixel_kernel.ROW_LIMIT + 1):
        values = rng.normal(0.0, 1.0, count) * 10.0 ** rng.uniform(-4, 4, count)
        assert subpixel_kernel._sum(values, 0, count) == values.sum()


def test_the_lu_solve_is_opencvs():
    rng = np.random.default_rng(4)
    for _ in range(20):
        design = rng.normal(0.0, 1.0, (60, 12))
        matrix, rhs = design.T @ design, rng.normal(0.0, 1.0, 12)
        solution = rhs.copy()
        assert subpixel_kernel._lu_solve(matrix.copy(), solution)
        solved, expected = cv2.solve(matrix, rhs, flags=cv2.DECOMP_LU)
        assert solved and np.array_equal(solution, expected[:, 0])
    assert not subpixel_kernel._lu_solve(np.zeros((12, 12)), np.zeros(12))


def test_a_fit_with_singular_equations_leaves_it_to_the_reference():
    # a tilted square's sides, but all of side 0's crossings on one point: its turn is not determined
    turn = np.radians(10.0)
    corners = (
        40.0
        * np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
        @ np.array([[np.cos(turn), np.sin(turn)], [-np.sin(turn), np.cos(turn)]])
    )
    along = np.linspace(0.1, 0.9, 12)[None, :, None]
    points = corners[:, None, :] + along * (np.roll(corners, -1, axis=0) - corners)[:, None, :]
    points[0] = points[0, 0]
    outward = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])
    weights = np.ones((4, 12))
    *_, solved = subpixel_kernel.fit_lines(points, weights, outward, points, 2, 0.1, 0.5)
    assert not solved
    long_rows = np.repeat(points, 11, axis=1)  # more crossings a side than the kernel sums
    assert not subpixel_kernel.fit_lines(long_rows, np.ones((4, 132)), outward, long_rows, 2, 0.1, 0.5)[3]
    with pytest.raises(np.linalg.LinAlgError):
        _fit_lines(points, weights, outward, points)
