import numpy as np
import pytest

from server.vlc.decoder import IdEvidence, read_stripes, row_time_s
from server.vlc.reader import read_id_frame


def decide(frames, **evidence_kwargs):
    evidence = IdEvidence(**evidence_kwargs)
    decisions = []
    for frame in frames:
        panels = [p for p in read_id_frame(frame).panels if p.observation is not None]
        assert len(panels) == 1
        evidence.add(panels[0].observation)
        decisions.append(evidence.decide())
    return decisions


@pytest.mark.parametrize("beacon_id, distance_m, exposure_s, frames", [
    (0xA5, 1.0, 1 / 8000, 4),
    (17, 2.0, 1 / 8000, 8),
    (254, 3.0, 1 / 8000, 12),
    (99, 1.5, 1 / 4000, 6),
])
def test_combined_frames_give_the_right_id_confidently(make_id_frames, beacon_id, distance_m, exposure_s, frames):
    decisions = decide(make_id_frames(beacon_id, distance_m, exposure_s, frames, seed=beacon_id))
    confident = [d for d in decisions if d.confident]
    assert confident, decisions[-1].message
    assert all(d.beacon_id == beacon_id for d in confident)
    # a 0.174 m panel never holds a whole 21-chip message in one frame: one frame is not enough
    assert not decisions[0].confident
    assert decisions[0].chips_seen < 21


def test_ten_millisecond_exposure_never_gives_a_confident_id(make_id_frames):
    frames = make_id_frames(42, 1.0, 0.01, 4, seed=3)
    # the frame itself says so: the code is averaged away
    assert "averaged away" in read_id_frame(frames[0]).problem


def test_long_exposure_stripes_forced_through_the_decoder_stay_unconfident(make_id_frames):
    evidence = IdEvidence()
    for frame in make_id_frames(42, 1.0, 0.01, 6, seed=4):
        reading = read_id_frame(frame.__class__(frame.pixels, frame.meta.model_copy(update={"exposure_s": 1e-4}),
                                                frame.camera))
        evidence.add(reading.panels[0].observation)
    assert not evidence.decide().confident


def test_a_code_outside_the_map_is_never_confident_and_is_said(make_id_frames):
    # ID 200 through a map with 201 (one bit away), then with 200 itself
    frames = make_id_frames(200, 1.4, 1 / 8000, 8, seed=5)
    foreign = decide(frames, map_ids=(17, 42, 99, 201))
    assert not any(d.confident for d in foreign)
    assert not foreign[-1].in_map and foreign[-1].beacon_id == 200  # what the stripes read
    assert foreign[-1].confidence > 0.99  # of "none of the map's"
    assert "none of the map's" in foreign[-1].message
    own = decide(frames, map_ids=(17, 42, 99, 200))
    assert own[-1].confident and own[-1].in_map and own[-1].beacon_id == 200
    # the map's 4 IDs and "none" decide no later than the 256 IDs alike
    first = next(i for i, d in enumerate(own) if d.confident)
    plain = decide(frames)
    assert first <= next((i for i, d in enumerate(plain) if d.confident), len(plain))


def test_none_is_as_likely_as_the_best_code_outside_the_map(make_id_frames):
    # one frame sees 13 chips: codes that differ only in the unseen ones fit alike, so a map ID can never
    # be surer than its prior against "none" (0.225 / (0.225 + 0.1)), whatever the frame shows
    frames = make_id_frames(17, 1.0, 1 / 8000, 1, seed=6)
    first = decide(frames, map_ids=(17, 42, 99, 200))[0]
    assert first.beacon_id == 17 and not first.confident
    assert first.confidence <= 0.225 / 0.325 + 1e-9
    assert IdEvidence(map_ids=(17, 42, 99, 200)).hypotheses == 5 and IdEvidence().hypotheses == 256


def test_stripes_skip_the_panel_edges_and_bin_rows():
    pixels = np.full((200, 100), 10, np.uint8)
    pixels[50:150, 20:80] = 200
    mask = pixels > 100
    obs = read_stripes(pixels, mask, (0, 0), 1.0, row_time_s(0.02, 200), 1e-4)
    assert obs is not None
    np.testing.assert_allclose(obs.values_dn, 200.0)
    rows = np.rint(obs.row_offsets_s / row_time_s(0.02, 200))
    assert rows.min() >= 53 and rows.max() <= 146  # 3-pixel margin inside the panel


def test_bad_timing_is_named():
    with pytest.raises(ValueError, match="rolling_shutter_skew_s"):
        row_time_s(0.0, 100)
    with pytest.raises(ValueError, match="exposure_s"):
        read_stripes(np.zeros((10, 10), np.uint8), np.ones((10, 10), bool), (0, 0), 0.0, 1e-5, 0.0)


def _observation(t_s, rows, row_time=1e-5, exposure_s=1e-4):
    from server.vlc.decoder import StripeObservation

    n = len(rows)
    return StripeObservation(t_s, exposure_s, np.array(rows, float)[:, None] * row_time, np.zeros(n), np.ones(n),
                             np.zeros(n), 1.0)


def test_burst_timing_tiles_the_message():
    from server.vlc.capture import message_period_s, stepped_interval_s

    period = message_period_s()
    for step in (0.25, 0.382):
        interval = stepped_interval_s(1 / 30, step=step)
        assert abs(interval - 1 / 30) < period
        assert (interval / period) % 1 == pytest.approx(step, abs=1e-9)
    with pytest.raises(ValueError, match="step"):
        stepped_interval_s(0.5, step=1.0)


def test_the_protocol_s_burst_is_four_frames_a_quarter_message_apart():
    # docs/vlc.md, "Capture protocol": 35.70 ms within a burst, captures 0.382 apart (498.81 ms)
    from server.vlc.capture import ID_BURST_FRAMES, ID_BURST_STEP, id_frame_interval_s, stepped_interval_s

    assert ID_BURST_FRAMES == 4 and ID_BURST_STEP == 0.25
    assert id_frame_interval_s() == pytest.approx(0.03570, abs=1e-8)
    assert stepped_interval_s(0.5) == pytest.approx(0.49881, abs=1e-5)


def test_the_id_frame_exposure_limit_comes_from_the_stripe_rules(make_id_frames):
    from server.vlc.capture import id_frame_problem
    from server.vlc.decoder import StripeRules

    frame = make_id_frames(0xA5, 1.0, 1 / 3000, 1, seed=1)[0]  # 0.83 chip
    assert id_frame_problem(frame) is None  # called with the frame alone: StripeRules' limit of one chip
    assert "averaged away" in id_frame_problem(frame, StripeRules(max_exposure_chips=0.5))
    longer = frame.__class__(frame.pixels, frame.meta.model_copy(update={"exposure_s": 1 / 2000}), frame.camera)
    assert "averaged away" in id_frame_problem(longer)


def _reference_log_likelihood(obs, reference_s, clock_errors_ppm, rules):
    """The likelihood as first written (all phases at once, one gather of every row's table entry): the
    reference `_frame_log_likelihood`'s blocks of phases are held to."""
    from server.vlc.codec import MESSAGE_CHIPS
    from server.vlc.decoder import ALL_IDS, _lookup

    lut = _lookup(ALL_IDS, round(obs.exposure_s, 9), rules.lut_steps_per_chip, rules.chip_rate_hz).T
    steps = lut.shape[1]
    chip_s = 1.0 / rules.chip_rate_hz
    period_s = MESSAGE_CHIPS * chip_s
    phases_s = np.arange(MESSAGE_CHIPS * rules.phase_steps_per_chip) * chip_s / rules.phase_steps_per_chip
    weights = 1.0 / obs.sigma_dn
    q, _ = np.linalg.qr(np.vander(obs.position, rules.trend_degree + 1) * weights[:, None])
    y = obs.values_dn * weights
    y_p = y - q @ (q.T @ y)
    level = float(np.mean(obs.values_dn))
    result = np.empty((lut.shape[0], len(phases_s), len(clock_errors_ppm)))
    for e, ppm in enumerate(clock_errors_ppm):
        times = (obs.timestamp_s - reference_s + obs.row_offsets_s) * (1.0 + ppm * 1e-6)
        index = ((phases_s[:, None, None] + times[None]) % period_s / period_s * steps).astype(np.int64) % steps
        raw = lut[:, index].mean(axis=-1)
        templates = raw * weights
        t_p = templates - (templates @ q) @ q.T
        norm = np.einsum("cpn,cpn->cp", t_p, t_p)
        along = t_p @ y_p
        gain = along / np.maximum(norm, 1e-12)
        bright = level + gain * (1.0 - raw.mean(axis=-1))
        plausible = (gain >= rules.min_depth * bright) & (norm > 1e-12)
        result[:, :, e] = float(y_p @ y_p) - np.where(plausible, along**2 / np.maximum(norm, 1e-12), 0.0)
    scale = max(1.0, float(result.min()) / max(1, obs.samples - rules.trend_degree - 2))
    return -0.5 * result / scale


@pytest.mark.parametrize("distance_m, bins", [(1.0, None), (2.5, 6)])
def test_the_frame_likelihood_equals_the_reference(make_id_frames, distance_m, bins):
    from dataclasses import replace

    from server.vlc.decoder import ALL_IDS, StripeRules, _frame_log_likelihood

    frame = make_id_frames(77, distance_m, 1 / 8000, 1, seed=5)[0]
    obs = next(p.observation for p in read_id_frame(frame).panels if p.observation is not None)
    if bins is not None:  # the fewest bins decoded
        obs = replace(obs, row_offsets_s=obs.row_offsets_s[:bins], values_dn=obs.values_dn[:bins],
                      sigma_dn=obs.sigma_dn[:bins], position=np.linspace(-1, 1, bins))
    rules, errors = StripeRules(), np.array([-40.0, 0.0, 40.0])
    fast = _frame_log_likelihood(obs, obs.timestamp_s - 0.02, ALL_IDS, errors, rules)
    reference = _reference_log_likelihood(obs, obs.timestamp_s - 0.02, errors, rules)
    # bit for bit: in each block every hypothesis's template is a row fitted by the same calls (exact ties kept)
    np.testing.assert_array_equal(fast, reference)
    assert fast.flags.c_contiguous  # decide() sums along the phases: a strided layout sums them in another order


def test_the_bounded_likelihood_weighs_every_hypothesis_as_fitting_them_all(make_id_frames):
    """Fits whose upper bounds lie `NEGLIGIBLE_LOG_LIKELIHOOD` below the best are not made: exp(value - best),
    all that `decide` reads of them, is 0 either way; every other value is the full fit's, bit for bit.
    Frames of two sizes (blocks of their own), three clock errors, a frame that shows fewer than a message."""
    from server.vlc.decoder import (ALL_IDS, NEGLIGIBLE_LOG_LIKELIHOOD, StripeRules, _frame_log_likelihood,
                                    _FrameFit, _total_log_likelihood)

    frames = make_id_frames(77, 1.0, 1 / 8000, 3, seed=5) + make_id_frames(77, 2.5, 1 / 8000, 2, seed=6)
    observations = [next(p.observation for p in read_id_frame(f).panels if p.observation is not None) for f in frames]
    rules, errors, reference = StripeRules(), np.array([-40.0, 0.0, 40.0]), observations[0].timestamp_s
    for count in (1, 2, len(observations)):
        fits = [_FrameFit(o, reference, ALL_IDS, errors, rules) for o in observations[:count]]
        assert count < len(observations) or len({fit.block for fit in fits}) == 2
        bounded = _total_log_likelihood(fits)
        full = sum(_frame_log_likelihood(o, reference, ALL_IDS, errors, rules) for o in observations[:count])
        exact = np.logical_and.reduce([fit.exact_phases() for fit in fits])
        assert not exact.all()  # the bound spared some fits
        assert np.all(bounded >= full)
        np.testing.assert_array_equal(bounded[:, exact], full[:, exact])
        assert bounded.max() == full.max()
        assert np.all(bounded[:, ~exact] < full.max() - NEGLIGIBLE_LOG_LIKELIHOOD)
        np.testing.assert_array_equal(np.exp(bounded - bounded.max()), np.exp(full - full.max()))


def test_decisions_are_those_of_fitting_every_hypothesis(make_id_frames, monkeypatch):
    import dataclasses

    import server.vlc.decoder as decoder

    def every_fit(fits):
        return sum(decoder._frame_log_likelihood(f.observation, f.reference_s, decoder.ALL_IDS, f.clock_errors_ppm,
                                                 f.rules) for f in fits)

    frames = make_id_frames(0xA5, 3.0, 1 / 8000, 5, seed=3)  # the faintest stripes: the loosest bounds
    maps = ((), (0xA5, 3, 200))
    bounded = {m: [dataclasses.astuple(d) for d in decide(frames, map_ids=m)] for m in maps}
    monkeypatch.setattr(decoder, "_total_log_likelihood", every_fit)
    for m in maps:
        assert [dataclasses.astuple(d) for d in decide(frames, map_ids=m)] == bounded[m]


def test_a_panel_s_pixels_are_counted_and_summed_as_numpy_does():
    from server.vlc.decoder import panel_pixels

    rng = np.random.default_rng(7)
    pixels = rng.integers(0, 256, (60, 80), dtype=np.uint8)
    mask = rng.random((40, 50)) < 0.9
    panel = panel_pixels(pixels, mask, (5, 7), 2)
    assert np.array_equal(panel.row_counts, panel.inner.sum(axis=1))
    assert np.array_equal(panel.column_counts, panel.inner.sum(axis=0))
    assert np.array_equal(panel.inside[panel.inner], pixels[5:45, 7:57][panel.inner].astype(np.float32))
    assert not panel.inside[~panel.inner].any() and np.array_equal(panel.row_sums, panel.inside.sum(axis=1))
