"""The track: fixes fed to the filter, and when it is trusted to predict."""

import numpy as np

from server.tracking.track import Track, TrackRules


def test_a_track_is_established_after_enough_accepted_fixes_and_predicts_the_walk():
    track = Track(TrackRules(established_fixes=2))
    assert track.predicted_m(0.0) is None and track.coasting(0.0) is None
    track.add(0.0, np.array([0.0, 0.0, 1.3]))
    assert not track.established and track.predicted_m(0.5) is None
    for k in range(1, 6):  # walking +x at 0.8 m/s
        state = track.add(0.5 * k, np.array([0.4 * k, 0.0, 1.3]))
    assert track.established and not state.outlier
    assert abs(state.velocity_mps[0] - 0.8) < 0.1
    assert abs(track.predicted_m(3.0)[0] - 2.4) < 0.05


def test_an_outlier_is_reported_not_fused_and_resets_the_trust():
    track = Track()
    for k in range(4):
        track.add(0.5 * k, np.array([0.0, 0.0, 1.3]))
    state = track.add(2.0, np.array([1.2, 0.0, 1.3]))  # a beacon spacing off: a wrong ID
    assert state.outlier and track.outliers == 1 and not track.established
    assert abs(state.filtered_position_m[0]) < 0.05


def test_a_silent_track_stops_predicting_but_still_coasts_for_the_answer():
    track = Track(TrackRules(horizon_s=2.4))
    for k in range(3):
        track.add(0.5 * k, np.array([0.0, 0.0, 1.3]))
    assert track.predicted_m(3.0) is not None
    assert track.predicted_m(4.0) is None
    assert track.coasting(4.0) is not None


def test_the_carried_flag_is_passed_through():
    track = Track()
    assert track.add(0.0, np.zeros(3), beacon_id_carried=True).beacon_id_carried


def test_the_fix_covariance_weighs_the_fix():
    sure, unsure = Track(), Track()
    for track, covariance in ((sure, np.eye(3) * 1e-6), (unsure, np.eye(3) * 1e-4)):
        for k in range(20):  # 1 s of video frames, 1 mm fixes
            track.add(0.05 * k, np.zeros(3), covariance_m2=np.eye(3) * 1e-6)
        track.add(1.0, np.array([0.004, 0.0, 0.0]), covariance_m2=covariance)
    assert unsure.state.position_m[0] < 0.5 * sure.state.position_m[0]


def test_a_clock_that_goes_back_predicts_nothing_and_starts_the_track_again():
    """A device replaying its frames under the same name sent times before the track's: a 500 once."""
    track = Track(TrackRules(established_fixes=2))
    for k in range(4):
        track.add(1.0 + 0.5 * k, np.array([0.4 * k, 0.0, 1.3]))
    assert track.established and track.predicted_m(0.0) is None and track.coasting(0.0) is None
    state = track.add(0.0, np.array([5.0, 0.0, 1.3]))
    assert state.filtered_position_m == [5.0, 0.0, 1.3] and not state.outlier
