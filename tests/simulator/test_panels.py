"""Real panels (`simulator.panels`): each effect does what it says on a simple scene, and the defaults draw
the bare panel exactly as before.

The scene: a 0.174 m panel 1 m straight above a distortion-free camera of fx = 1000 px (1 mm = 1 px at
the panel), the PSF 0.5 px, the panel at 100 cd/m2 (102 DN: nothing clips); levels are the renderer's
noiseless light (`render_signal`).
"""

import hashlib

import numpy as np
import pytest

from shared_schemas import Beacon
from simulator.bench_robustness import panel_effects
from simulator.benchmarks import AccuracyConfig, accuracy_frame
from simulator.chain import ChainSpec
from simulator.panels import PanelSpec, edge_profile, offset_beacon, panel_bands, ring, sheen_profile
from simulator.render import CameraPose, coverage_map, render_signal
from simulator.scene import Scene, scene_emitters

SIZE = 320
CENTRE = (SIZE - 1) / 2  # the panel's centre in the frame, both axes
EDGE_PX = CENTRE + 87.0  # its right edge along the centre row (half of 0.174 m at 1000 px / m)
UP = CameraPose(np.zeros(3), np.eye(3))


def scene(panel: PanelSpec | None = None, lights: list | None = None, psf_sigma_px: float = 0.5) -> Scene:
    return Scene.model_validate({
        "name": "real",
        "room": {"size_m": [2.0, 2.0, 1.0], "origin_m": [-1.0, -1.0, 0.0]},
        "beacons": [{"id": 1, "center_m": [0.0, 0.0, 1.0], "luminance_nits": 100.0,
                     "panel": None if panel is None else panel.model_dump()}],
        "camera": {"profile": None, "width": SIZE, "height": SIZE, "pixel_size_m": 2e-6, "focal_length_m": 2e-3},
        "sensor": {"psf_sigma_px": psf_sigma_px},
        "light_sources": lights or [],
    })


def light(s: Scene, pose: CameraPose = UP) -> np.ndarray:
    """The noiseless light above the background (height, width)."""
    model = s.sensor.model()
    return render_signal(scene_emitters(s, pose), SIZE, SIZE, model) - model.background_dn


LEVEL_DN = 100.0 * 0.01 * 102.0  # luminance x exposure x DN per cd/m2 s (simulator.scene's photometry)


def test_defaults_draw_the_bare_panel_as_before():
    assert panel_bands(PanelSpec(), 0.087) == [(0.0, 1.0)]
    bare, off = scene(), scene(PanelSpec())
    assert [len(e.outline_px) for e in scene_emitters(off, UP)] == [len(e.outline_px) for e in scene_emitters(bare, UP)]
    np.testing.assert_array_equal(light(off), light(bare))
    assert '"panel"' not in bare.to_json() and '"panel"' in scene(PanelSpec.typical()).to_json()
    assert Scene.model_validate_json(off.to_json()) == off
    # the accuracy bench's frames as before panels existed (hashes at 56f724a), with and without a chain
    frames = [accuracy_frame(AccuracyConfig(scale=0.1, chain=chain, panel=panel), 0)[0].pixels
              for chain in (None, ChainSpec()) for panel in (None, PanelSpec())]
    digests = [hashlib.sha256(frame.tobytes()).hexdigest()[:16] for frame in frames]
    assert digests == [BEFORE_PLAIN] * 2 + [BEFORE_CHAIN] * 2


BEFORE_PLAIN = "39e1a761eb061034"
BEFORE_CHAIN = "3ad76bca5de8e7d0"


def test_offsets_are_the_exact_offsets_of_the_map_shapes():
    square = Beacon(id=0, center_m=[0.0, 0.0, 1.0], side_m=0.174, corner_radius_m=0.02)
    grown, shrunk = offset_beacon(square, 0.01), offset_beacon(square, -0.03)
    assert (grown.side_m, grown.corner_radius_m) == pytest.approx((0.194, 0.03))
    assert (shrunk.side_m, shrunk.corner_radius_m) == pytest.approx((0.114, 0.0))  # the corner's arc is used up
    disc = Beacon(id=0, center_m=[0.0, 0.0, 1.0], shape="circle", diameter_m=0.2)
    assert offset_beacon(disc, -0.01).diameter_m == pytest.approx(0.18)
    assert offset_beacon(square, 0.0) is square


def test_a_ring_covers_the_outer_outline_less_the_inner_exactly():
    angles = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    circle = np.column_stack([np.cos(angles), np.sin(angles)])
    outer, inner = 40.3 + 30.2 * circle, 40.3 + 17.7 * circle
    np.testing.assert_allclose(coverage_map(ring(outer, inner), 80, 80),
                               coverage_map(outer, 80, 80) - coverage_map(inner, 80, 80), atol=1e-5)


def test_bezel_ring_has_its_level_and_width():
    bezel = PanelSpec.typical("white").only("bezel")
    assert (bezel.bezel_width_m, bezel.bezel_fraction) == (0.01, 0.03)
    assert PanelSpec.typical("metal").bezel_fraction < bezel.bezel_fraction
    added = (light(scene(bezel)) - light(scene()))[int(CENTRE)]  # the centre row
    right = added[int(CENTRE) + 1:]
    # the ring's middle, 5 px outside the edge, at 3 % of the panel; nothing changes inside the panel
    assert added[round(EDGE_PX + 5)] == pytest.approx(0.03 * LEVEL_DN, rel=1e-3)
    assert np.abs(added[round(CENTRE) - 80:round(EDGE_PX) - 3]).max() < 1e-4
    assert right.sum() / (0.03 * LEVEL_DN) == pytest.approx(10.0, abs=0.05)  # 10 mm = 10 px wide


def test_edge_falloff_darkens_the_edge_by_the_spec_ratio():
    falloff = PanelSpec.typical().only("falloff")
    assert (falloff.edge_ratio, falloff.falloff_width_m) == (0.8, 0.03)
    assert edge_profile(falloff, 0.0) == 0.8 and edge_profile(falloff, 0.03) == edge_profile(falloff, 0.08) == 1.0
    row = light(scene(falloff))[int(CENTRE)]
    assert row[round(CENTRE)] == pytest.approx(LEVEL_DN, rel=1e-4)  # the centre keeps the panel's level
    for depth_px in (2.5, 6.5, 14.5, 24.5):  # pixel centres inside the right edge, beyond the PSF's reach
        expected = edge_profile(falloff, depth_px / 1000)
        # drawn in 8 bands of 3.75 px, each at the profile's middle: within half a band's change
        assert row[round(EDGE_PX - depth_px)] / row[round(CENTRE)] == pytest.approx(expected, abs=0.01)
    assert row[round(EDGE_PX - 2.5)] < row[round(EDGE_PX - 6.5)] < row[round(EDGE_PX - 14.5)] < row[round(CENTRE)]


def test_glossy_ceiling_sheen_falls_off_with_distance():
    sheen = PanelSpec.typical(glossy_ceiling=True).only("sheen")
    assert (sheen.sheen_fraction, sheen.sheen_length_m) == (0.02, 0.03)
    row = light(scene(sheen, psf_sigma_px=2.0), CameraPose(np.array([0.1, 0.0, 0.0]), np.eye(3)))[int(CENTRE)]
    edge_px = EDGE_PX - 100  # the camera 0.1 m to the right: the panel 100 px to the left
    distances_px = [7.5, 22.5, 52.5, 97.5]  # band middles, 15 px bands: beyond the PSF's reach of their edges
    measured = [row[round(edge_px + d)] for d in distances_px]
    assert measured == sorted(measured, reverse=True)
    for d, value in zip(distances_px, measured, strict=True):
        assert value == pytest.approx(sheen_profile(sheen, d / 1000) * LEVEL_DN, rel=1e-2)  # the panel's PSF tail
    assert measured[0] / LEVEL_DN == pytest.approx(0.02 * np.exp(-0.25), rel=1e-2)
    assert row[round(edge_px + 125)] == pytest.approx(0.0, abs=1e-3)  # beyond 4 lengths: the bare ceiling


def test_a_second_lamp_appears_where_it_should():
    lamp = {"kind": "disc", "center_m": [0.12, -0.11, 1.0], "radius_m": 0.02, "luminance_nits": 50.0}
    added = light(scene(lights=[lamp])) - light(scene())
    rows, cols = np.indices(added.shape)
    total = added.sum()
    # centred at its projection (fx = 1000 px, looking straight up, image x = map X, y = map Y)
    assert (cols * added).sum() / total == pytest.approx(CENTRE + 120, abs=0.05)
    assert (rows * added).sum() / total == pytest.approx(CENTRE - 110, abs=0.05)
    assert total == pytest.approx(np.pi * 20**2 * 50 * 0.01 * 102, rel=2e-3)  # its area x its level


def test_the_bench_panel_cells_keep_the_pose_and_change_the_frame():
    base = AccuracyConfig(distance_m=1.0, frames=1, scale=0.1, chain=ChainSpec())
    plain, _, pose = accuracy_frame(base, 0)
    for name, fields in panel_effects(1.0).items():
        frame, _, cell_pose = accuracy_frame(AccuracyConfig(**{**base.__dict__, **fields}), 0)
        np.testing.assert_array_equal(cell_pose.rotation_wc, pose.rotation_wc)
        assert frame.meta.gravity_camera == plain.meta.gravity_camera
        if name != "window":  # out of this frame's view
            assert not np.array_equal(frame.pixels, plain.pixels), name
