"""The scene spec: validation naming the field, photometry, rendering and metadata."""

import json

import numpy as np
import pytest
from pydantic import ValidationError

from simulator.render import CameraPose
from simulator.scene import SCENES_DIR, Scene, find_scene, load_scene, render_sample, scene_emitters

SMALL = {
    "name": "small",
    "room": {"size_m": [2.0, 2.0, 1.0], "origin_m": [-1.0, -1.0, 0.0]},
    "beacons": [{"id": 3, "center_m": [0.0, 0.0, 1.0]}],
    "camera": {"profile": "xiaomi-mi8-front", "scale": 0.1},
}
UP = CameraPose(np.zeros(3), np.eye(3))


def scene(**changes) -> Scene:
    return Scene.model_validate({**SMALL, **changes})


@pytest.mark.parametrize("path", sorted(SCENES_DIR.glob("*.json")), ids=lambda p: p.stem)
def test_bundled_scenes_validate_and_round_trip(path):
    loaded = load_scene(path)
    assert Scene.model_validate_json(loaded.to_json()) == loaded
    assert find_scene(path.stem) == loaded


@pytest.mark.parametrize("change, field", [
    ({"camera": {"profile": "nokia-3310"}}, "unknown device profile"),
    ({"camera": {"profile": None, "width": 100, "height": 80}}, "pixel_size_m, focal_length_m"),
    ({"camera": {"distortion": [0.1, 0.2]}}, "distortion"),
    ({"beacons": [{"id": 3, "center_m": [0, 0, 1.0]}, {"id": 3, "center_m": [0.5, 0, 1.0]}]}, "unique"),
    ({"beacons": [{"id": 3, "center_m": [0, 0, 1.5]}]}, "outside the room"),
    ({"beacons": [{"id": 3, "center_m": [0, 0, 1.0], "corner_radius_m": 0.1}]}, "corner_radius_m"),
    ({"light_sources": [{"kind": "polygon", "points_m": [[0, 0, 1], [1, 0, 1]]}]}, "at least 3 points_m"),
    ({"sensor": {"iso": 10}}, "iso"),
    ({"name": "a b"}, "name"),
    ({"colour": "red"}, "colour"),
])
def test_bad_scene_names_the_problem(change, field):
    with pytest.raises(ValidationError, match=field):
        scene(**change)


def test_unknown_scene_name_lists_the_bundled_ones():
    with pytest.raises(ValueError, match="paper-bench"):
        find_scene("no-such-scene")


def test_photometry_saturates_at_10ms_iso100_and_gain_scales_noise():
    bench = find_scene("paper-bench")
    [panel] = scene_emitters(bench, UP)
    assert panel.level_dn == pytest.approx(1020.0)  # 1000 cd/m2 x 10 ms x 102 DN/(cd/m2 s): 4x saturation
    loud = bench.sensor.model_copy(update={"iso": 400})
    assert loud.model().electrons_per_dn == pytest.approx(bench.sensor.model().electrons_per_dn / 4)
    assert loud.model().read_noise_dn == pytest.approx(4 * bench.sensor.model().read_noise_dn)


def test_general_camera_and_overrides():
    general = scene(camera={"profile": None, "width": 400, "height": 300, "pixel_size_m": 2e-6,
                            "focal_length_m": 4e-3, "cx": 210.0, "distortion": [0.01, 0, 0, 0]})
    camera = general.camera.intrinsics()
    assert camera.fx == pytest.approx(2000.0)
    assert (camera.cx, camera.cy, camera.distortion) == (210.0, 149.5, [0.01, 0, 0, 0])
    longer = scene(camera={"profile": "xiaomi-mi8-front", "scale": 0.1, "focal_length_m": 3.52e-3 * 1.05})
    assert longer.camera.intrinsics().fx == pytest.approx(scene().camera.intrinsics().fx * 1.05)


def test_render_sample_is_deterministic_and_carries_the_truth():
    small = scene(sensor={"exposure_s": 0.002, "iso": 200, "rolling_shutter_skew_s": 0.02})
    pose = CameraPose(np.array([0.05, -0.02, 0.0]), np.eye(3))
    a, meta = render_sample(small, pose, np.random.default_rng(1), t_s=0.25, note="x")
    b, _ = render_sample(small, pose, np.random.default_rng(1), t_s=0.25)
    np.testing.assert_array_equal(a, b)
    assert a.shape == (518, 388) and a.max() == 255
    assert (meta.exposure_s, meta.iso, meta.rolling_shutter_skew_s, meta.timestamp_ns) == (0.002, 200, 0.02, 250_000_000)
    assert meta.ground_truth.position_m == [0.05, -0.02, 0.0]
    assert meta.gravity_camera == pytest.approx([0, 0, -1], abs=0.01)
    assert json.loads(meta.model_dump_json())["note"] == "x"


def test_light_sources_and_vignetting_show_in_the_frame():
    dark = scene(sensor={"read_noise_dn_iso100": 0.0, "electrons_per_dn_iso100": 1e9, "ambient_nits": 100.0})
    lamp = {"kind": "disc", "center_m": [0.3, 0.3, 1.0], "radius_m": 0.05, "luminance_nits": 100.0}
    lit, _ = render_sample(scene(**{**dark.model_dump(), "light_sources": [lamp]}), UP, np.random.default_rng(0))
    plain, _ = render_sample(dark, UP, np.random.default_rng(0))
    row, col = round(259 + 0.3 * 391.1), round(193.5 + 0.3 * 391.1)  # the disc centre in the image
    assert int(lit[row, col]) - int(plain[row, col]) == pytest.approx(102, abs=2)
    vignetted = dark.model_copy(update={"sensor": dark.sensor.model_copy(update={"vignetting": 0.4})})
    corner, _ = render_sample(vignetted, UP, np.random.default_rng(0))
    assert corner[0, 0] == pytest.approx(0.6 * 4 + 0.6 * 102, abs=1.5) and plain[0, 0] == pytest.approx(106, abs=1)


def test_vlc_code_stripes_a_short_exposure_only():
    coded = [{"id": 3, "center_m": [0.0, 0.0, 1.0], "vlc_code": 3, "luminance_nits": 8000.0}]
    short = scene(beacons=coded, sensor={"exposure_s": 1 / 8000, "iso": 400})
    image, _ = render_sample(short, UP, np.random.default_rng(0))
    column = image[230:290, 194].astype(float)  # the panel's middle rows
    assert column.max() == 255 and column.min() < 200  # dark chips between bright ones
    steady = scene(beacons=[{**coded[0], "vlc_code": None}], sensor={"exposure_s": 1 / 8000, "iso": 400})
    image, _ = render_sample(steady, UP, np.random.default_rng(0))
    assert image[230:290, 194].min() == 255


def test_a_beacon_s_vlc_depth_sets_how_dark_its_led_goes_between_chips():
    # depth 1.0: an LED keyed fully off (OOK, full-depth PWM); the default 0.7 keeps it at 0.3 of its level
    coded = {"id": 3, "center_m": [0.0, 0.0, 1.0], "vlc_code": 3, "luminance_nits": 3000.0}
    darkest = {}
    for depth in (None, 1.0):
        spec = coded if depth is None else {**coded, "vlc_depth": depth}
        image, _ = render_sample(scene(beacons=[spec], sensor={"exposure_s": 1 / 8000, "iso": 400}), UP,
                                 np.random.default_rng(0))
        column = image[230:290, 194].astype(float)  # the panel's middle rows
        darkest[depth] = column.min() / column.max()
    assert darkest[None] > 0.2 and darkest[1.0] < 0.1
    with pytest.raises(ValidationError):
        scene(beacons=[{**coded, "vlc_depth": 1.5}])
