import numpy as np
import pytest

from server.vlc.codec import LedWaveform, encode
from simulator.led import row_gains


def test_short_exposure_rows_follow_the_chips():
    wave = LedWaveform.for_beacon(200, low_level=0.2)
    row_time = wave.chip_s / 10  # 10 rows per chip
    gains = row_gains(wave, 210, row_time, exposure_s=1e-7)
    chips = gains[5::10] > 0.6  # chip centres
    np.testing.assert_array_equal(chips, encode(200).astype(bool))


def test_row_gain_is_the_box_average_of_the_waveform():
    wave = LedWaveform.for_beacon(3)
    gains = row_gains(wave, 50, 2e-5, exposure_s=3e-4, start_s=0.0123)
    for r in (0, 17, 49):
        t = 0.0123 + r * 2e-5 + np.linspace(0, 3e-4, 20001)
        brute = wave.window_means(t[:-1], 1e-9).mean()
        assert gains[r] == pytest.approx(brute, abs=2e-3)


def test_ten_millisecond_exposure_averages_the_code_away():
    wave = LedWaveform.for_beacon(85)
    gains = row_gains(wave, 1296, 0.03 / 1295, exposure_s=0.01)
    short = row_gains(wave, 1296, 0.03 / 1295, exposure_s=1 / 8000)
    assert np.ptp(gains) < 0.1 * np.ptp(short)


@pytest.mark.parametrize("kwargs", [{"height": 0}, {"exposure_s": 0.0}, {"row_time_s": -1.0}])
def test_bad_arguments_name_the_field(kwargs):
    args = {"height": 10, "row_time_s": 1e-5, "exposure_s": 1e-4} | kwargs
    name = next(iter(kwargs))
    with pytest.raises(ValueError, match=name):
        row_gains(LedWaveform.for_beacon(1), **args)
