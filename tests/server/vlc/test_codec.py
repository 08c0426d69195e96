import numpy as np
import pytest

from server.vlc.codec import DEFAULT_DEPTH, HEADER, MESSAGE_CHIPS, LedWaveform, decode, encode, header_starts


def _longest_run(chips) -> int:
    best = run = 1
    for a, b in zip(chips[:-1], chips[1:]):
        run = run + 1 if a == b else 1
        best = max(best, run)
    return best


def test_every_id_round_trips_at_every_rotation():
    for beacon_id in range(256):
        chips = encode(beacon_id)
        assert len(chips) == MESSAGE_CHIPS
        for shift in range(MESSAGE_CHIPS):
            assert decode(np.roll(chips, shift)) == beacon_id


def test_header_never_occurs_in_data_or_across_the_boundary():
    for beacon_id in range(256):
        chips = encode(beacon_id)
        assert header_starts(chips) == [0]
        assert _longest_run(chips[len(HEADER):]) <= 2
        # two messages back to back: headers only where messages start
        assert header_starts(np.concatenate([chips, chips])) == [0, MESSAGE_CHIPS]


def test_every_message_is_nearly_dc_balanced():
    assert {int(encode(i).sum()) for i in range(256)} <= {11, 12}


def test_all_messages_differ_at_every_rotation():
    rotations = {tuple(np.roll(encode(i), s)): i for i in range(256) for s in range(MESSAGE_CHIPS)}
    assert len(rotations) == 256 * MESSAGE_CHIPS


def test_corrupted_messages_are_refused_not_misread():
    chips = encode(0xA5)
    for k in range(MESSAGE_CHIPS):
        flipped = chips.copy()
        flipped[k] ^= 1
        assert decode(flipped) != 0xA5
    assert decode(chips[:-1]) is None
    assert decode(np.full(MESSAGE_CHIPS, 2)) is None


@pytest.mark.parametrize("bad", [-1, 256, 3.0, True])
def test_bad_ids_are_named(bad):
    with pytest.raises((ValueError, TypeError), match="beacon_id"):
        encode(bad)


def test_window_means_average_the_code_over_long_windows():
    wave = LedWaveform.for_beacon(77)
    starts = np.linspace(0.0, 0.05, 101)
    short = wave.window_means(starts, 1e-6)
    assert set(np.round(short, 6)) <= {wave.low_level, wave.high_level}
    whole = wave.window_means(starts, 10 * wave.period_s)
    np.testing.assert_allclose(whole, wave.mean_level, atol=1e-9)


def test_the_default_low_level_is_the_default_depth_s():
    assert LedWaveform.for_beacon(77).depth == pytest.approx(DEFAULT_DEPTH, abs=1e-12)
    assert LedWaveform.for_beacon(77) == LedWaveform.for_beacon(77, depth=DEFAULT_DEPTH)


def test_a_depth_and_a_low_level_together_are_refused_not_one_silently_kept():
    with pytest.raises(ValueError, match="depth or low_level"):
        LedWaveform.for_beacon(77, depth=1.0, low_level=0.2)

