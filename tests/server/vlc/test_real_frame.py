"""The stripe measurement on a real rolling-shutter frame with a known signal, and on rendered ones.

The real frame (tests/fixtures/rolling_shutter/README.md): a Nikon 1 J1 at 1/16000 s looking
through a diffuser at an LED keyed at 1000 Hz, 50 % duty; 15.730 ms from the first row to the
last of its 1080. It is not our line code: the decoder must name nothing in it.
"""

from pathlib import Path

import cv2
import numpy as np
import pytest

from server.camera import intrinsics_from_profile
from server.geometry import rotation_from_ypr
from server.ingest import LumaFrame
from server.locator import locate
from server.vlc.codec import LedWaveform
from server.vlc.decoder import IdEvidence, read_stripes, row_time_s
from server.vlc.reader import read_id_frame
from server.vlc.stripes import NoStripes, StripeMeasurement, measure_stripes, row_signal
from shared_schemas import (
    Beacon,
    BeaconMap,
    CameraIntrinsics,
    FrameFormat,
    FrameKind,
    FrameMeta,
    device_profiles,
)
from simulator.led import row_gains
from simulator.render import CameraPose, SensorModel, render_frame

FRAME = Path(__file__).parents[2] / "fixtures" / "rolling_shutter" / "nikon1j1_1000hz_luma.png"
SKEW_S = 15.730e-3  # the repository's readout of the 1080p30 clip, first row to last
EXPOSURE_S = 1 / 16000
BLINK_HZ = 1000.0


@pytest.fixture(scope="module")
def real_pixels() -> np.ndarray:
    pixels = cv2.imread(str(FRAME), cv2.IMREAD_UNCHANGED)
    assert pixels is not None and pixels.shape == (1080, 1920) and pixels.dtype == np.uint8
    return pixels


def as_uploaded(pixels: np.ndarray) -> LumaFrame:
    """The frame as the server builds it from an upload: a PNG ID frame with the camera's facts (the
    intrinsics are a guess: the stripes do not use them)."""
    height, width = pixels.shape
    camera = CameraIntrinsics(fx=1.2 * width, fy=1.2 * width, cx=width / 2, cy=height / 2)
    meta = FrameMeta(format=FrameFormat.png, width=width, height=height, camera=camera, exposure_s=EXPOSURE_S,
                     rolling_shutter_skew_s=SKEW_S, timestamp_ns=0, frame_kind=FrameKind.id)
    pixels = np.ascontiguousarray(pixels)
    pixels.flags.writeable = False
    return LumaFrame(pixels, meta, camera)


def measure_whole(pixels: np.ndarray) -> StripeMeasurement:
    """The whole frame is the diffuser: its every row, read as the decoder reads a panel's."""
    row_time = row_time_s(SKEW_S, pixels.shape[0])
    signal = row_signal(pixels, np.ones(pixels.shape, bool), (0, 0), row_time, EXPOSURE_S)
    assert signal is not None
    measured = measure_stripes(*signal, row_time, EXPOSURE_S)
    assert isinstance(measured, StripeMeasurement), measured
    return measured


def test_real_frame_blink_frequency_within_0p2_percent(real_pixels):
    measured = measure_whole(real_pixels)
    assert measured.rising_edges >= 15 and measured.falling_edges >= 15  # 15.7 periods in view
    assert abs(measured.frequency_hz / BLINK_HZ - 1) < 0.002, measured
    # the fit's own error is far below that; the readout it rests on is known to 0.004 ms in 15.73 (0.03 %)
    assert measured.frequency_hz_sigma < 0.0005 * BLINK_HZ


def test_real_frame_duty_within_3_percent(real_pixels):
    # at the half level of the frame's values: 52.4 %. The camera's tone curve lifts the half level's
    # light to about a fifth, so each bright run looks ~1.2 rows longer at both ends; undoing an sRGB
    # curve gives 50.1 % (docs/vlc.md, "A real frame")
    measured = measure_whole(real_pixels)
    assert abs(measured.duty - 0.5) < 0.03, measured


def test_real_frame_edge_width_as_the_exposure_predicts(real_pixels):
    measured = measure_whole(real_pixels)
    # a box of 1/16000 s over rows 14.578 us apart: a ramp of 4.29 rows, 10-90 % in 3.43 rows
    assert measured.predicted_width_rows == pytest.approx(0.8 * EXPOSURE_S * 1079 / SKEW_S)
    assert measured.predicted_width_rows == pytest.approx(3.43, abs=0.01)
    # measured 3.22 (rising) and 3.16 (falling): 6-8 % narrower, no wider as a blur would make it (the
    # camera sharpens: its edges overshoot by 1-2 DN; and clips its blacks at 0); within 10 %
    for width in (measured.rise_width_rows, measured.fall_width_rows):
        assert abs(width / measured.predicted_width_rows - 1) < 0.10, measured
    # a rising and a falling edge spread alike, as a box exposure spreads both
    assert abs(measured.rise_width_rows - measured.fall_width_rows) < 0.2


def test_real_frame_gives_no_confident_id(real_pixels):
    frame = as_uploaded(real_pixels)
    reading = read_id_frame(frame)
    assert reading.problem is None
    # the LED is keyed fully off, but its dark runs (34 rows) are shorter than the longest our code allows
    # (2 chips + the exposure: 59 rows at this row time), so the bars are bridged into one blob, as our own
    # LEDs' are at full depth (docs/vlc.md, "Modulation depth")
    assert len(reading.panels) == 1
    observations = [p.observation for p in reading.panels if p.observation is not None]
    # also the whole diffuser as one panel, as a reader that joins bars across dark rows would give it
    row_time = row_time_s(SKEW_S, 1080)
    whole = read_stripes(frame.pixels, np.ones((1080, 1920), bool), (0, 0), 0.0, row_time, EXPOSURE_S)
    assert whole is not None and whole.chips_seen > 21
    assert observations
    for observation in observations:
        for map_ids in ((), (1, 2, 3, 42)):
            evidence = IdEvidence(map_ids=map_ids)
            evidence.add(observation)
            assert not evidence.decide().confident
    # a 1 kHz square wave is no code at any phase: no ID at all, not the prior's favourite as a posterior
    for map_ids in ((), (1, 2, 3, 42)):
        evidence = IdEvidence(map_ids=map_ids)
        evidence.add(whole)
        decision = evidence.decide()
        assert not decision.confident
        assert decision.beacon_id is None and "no code fits the stripes" in decision.message, decision.message


def test_real_frame_turned_is_said_to_look_turned(real_pixels):
    turned = as_uploaded(real_pixels.T)  # 1080 x 1920: the stripes run along the columns
    reading = read_id_frame(turned)
    assert reading.panels == ()
    assert reading.problem is not None and "stripes run along columns" in reading.problem
    assert "turned 90 degrees" in reading.problem
    # the frame as taken is not
    assert read_id_frame(as_uploaded(real_pixels)).problem is None


def test_real_frame_through_locate_names_no_panel_and_says_turned(real_pixels):
    room = BeaconMap(name="room", beacons=[Beacon(id=i, center_m=[2.0 * i, 0.0, 2.5], side_m=0.6) for i in (17, 42)])
    taken = locate(as_uploaded(real_pixels), room)
    assert not taken.ok and "no panel with a confidently read ID" in taken.message
    assert taken.vlc is None or not taken.vlc.confident
    turned = locate(as_uploaded(real_pixels.T), room)
    assert not turned.ok and "is the frame turned 90 degrees?" in turned.message


# rendered: a panel filling a small frame, lit by a square wave of known frequency and duty
WIDTH, HEIGHT = 120, 640
RENDER_SKEW_S = 0.0099  # 15.5 us a row, as the real frame's 14.6: a 1 kHz period is 64.5 rows, 9.9 in view


def rendered(duty_tenths: int, low_level: float, exposure_s: float, seed: int) -> np.ndarray:
    camera = intrinsics_from_profile(device_profiles()["xiaomi-mi8-front"], WIDTH, HEIGHT)
    beacon = Beacon(id=1, center_m=[0.0, 0.0, 0.5], side_m=2.0)  # far wider than the view
    chips = (1,) * duty_tenths + (0,) * (10 - duty_tenths)
    rng = np.random.default_rng(seed)
    wave = LedWaveform(chips, chip_rate_hz=10 * BLINK_HZ, low_level=low_level, phase_s=rng.uniform(0, 1e-3))
    gains = row_gains(wave, HEIGHT, RENDER_SKEW_S / (HEIGHT - 1), exposure_s, 0.0)
    sensor = SensorModel(background_dn=3.0, plateau_dn=200.0, psf_sigma_px=1.2, electrons_per_dn=4.0,
                         read_noise_dn=2.0)
    pose = CameraPose(np.zeros(3), rotation_from_ypr(0.0, 0.0, 0.0))
    return render_frame(beacon, camera, pose, WIDTH, HEIGHT, sensor, rng, row_gain=gains)


@pytest.mark.parametrize(
    ("duty_tenths", "low_level", "exposure_s", "seed"),
    [(5, 0.0, 1 / 16000, 1), (3, 0.3, 1 / 8000, 2), (7, 0.0, 1 / 8000, 3)],
)
def test_rendered_square_wave_is_measured(duty_tenths, low_level, exposure_s, seed):
    pixels = rendered(duty_tenths, low_level, exposure_s, seed)
    row_time = row_time_s(RENDER_SKEW_S, HEIGHT)
    signal = row_signal(pixels, np.ones(pixels.shape, bool), (0, 0), row_time, exposure_s)
    assert signal is not None
    measured = measure_stripes(*signal, row_time, exposure_s)
    assert isinstance(measured, StripeMeasurement), measured
    assert abs(measured.frequency_hz / BLINK_HZ - 1) < 0.002, measured
    assert abs(measured.duty - duty_tenths / 10) < 0.01, measured
    # the renderer's rows are exact box averages: the edges spread as the exposure says (to the
    # interpolation between rows: +0.02-0.08 row at a 4-row ramp, +0.3 at 2 rows)
    assert abs(measured.edge_width_rows / (0.8 * exposure_s / row_time) - 1) < 0.05, measured


def test_plain_rows_are_no_stripes():
    rng = np.random.default_rng(0)
    values = 150 + rng.normal(0, 2, 200)
    assert isinstance(measure_stripes(np.arange(200), values, 2e-5, 1e-4), NoStripes)


def test_vlc_stripes_command_measures_the_real_frame(capsys):
    import json

    from lumipose_cli.main import main

    args = ["vlc", "stripes", str(FRAME), "--skew-s", str(SKEW_S), "--exposure-s", str(EXPOSURE_S), "--json"]
    assert main(args) == 0
    body = json.loads(capsys.readouterr().out)
    assert abs(body["frequency_hz"] / BLINK_HZ - 1) < 0.002 and abs(body["duty"] - 0.5) < 0.03
    assert body["predicted_width_rows"] == pytest.approx(3.43, abs=0.01)
    # undoing an sRGB curve puts the half level at half the light: the duty comes to the LED's 50 %
    assert main([*args, "--tone-curve", "srgb"]) == 0
    assert abs(json.loads(capsys.readouterr().out)["duty"] - 0.5) < 0.005
