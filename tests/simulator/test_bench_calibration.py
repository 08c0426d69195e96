"""`lumipose bench calibration` end to end on a few small photos (the full-size figures: docs/calibration.md)."""

from lumipose_cli.main import main
from server.calibration.lens import Lens
from simulator.bench_calibration import PHONE_K3, bench_calibration, bench_real_lens, format_calibration, phone_lens
from simulator.bench_grid import RealBench, real_bench_scene


def test_a_few_views_run_through_and_are_refused_for_their_number():
    result = bench_calibration(views=3, scale=0.25, seed=2, poor_sets=False)
    good = result["good"]
    assert good["views"] == 3 and not good["ok"] and "fx_error_pct" not in good
    asked = f"more photos: {good['views_found']} with the board found"
    assert any(advice.startswith(asked) for advice in good["advice"])
    assert "good set REFUSED: more photos" in format_calibration(result)


def test_the_bench_real_lens_is_the_bench_reals_camera():
    lens, width, height = bench_real_lens(0.25)
    camera = real_bench_scene(RealBench(), 0.25).camera
    intrinsics = camera.intrinsics()
    assert (width, height) == camera.frame_size()
    assert (lens.fx, lens.cx, lens.distortion[:2]) == (intrinsics.fx, intrinsics.cx, tuple(intrinsics.distortion[:2]))


def test_bad_options_are_refused(capsys):
    assert main(["bench", "calibration", "--views", "2"]) == 2
    assert "--views must be at least 3" in capsys.readouterr().err
    assert main(["bench", "calibration", "--views", "10", "--corner-views", "11"]) == 2
    assert "--corner-views within 0..views" in capsys.readouterr().err


def test_the_k3_lens_is_the_phone_lens_with_k3():
    phone, width, height = phone_lens(0.25)
    with_k3, width_k3, height_k3 = phone_lens(0.25, PHONE_K3)
    assert (width, height) == (width_k3, height_k3) and phone.distortion[4] == 0 and PHONE_K3 != 0
    assert with_k3 == Lens(phone.fx, phone.fy, phone.cx, phone.cy, (*phone.distortion[:4], PHONE_K3))
