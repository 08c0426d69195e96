import numpy as np
import pytest

from server.tracking.filter import FilterRules, predict, start, update


def test_constant_velocity_walk_is_followed_and_its_speed_learnt():
    rng = np.random.default_rng(0)
    velocity = np.array([0.8, -0.3, 0.0])
    state = start(0.0, np.zeros(3))
    for k in range(1, 20):
        t = 0.5 * k
        step = update(state, t, velocity * t + rng.normal(0, 0.003, 3))
        assert step.accepted and not step.restarted
        state = step.state
    # a walker's filter (1.5 m/s^2 process noise) trusts the last fixes: its speed is good to ~0.1 m/s
    assert np.all(np.abs(state.velocity_mps - velocity) < 2 * np.sqrt(np.diag(state.covariance))[3:])
    np.testing.assert_allclose(predict(state, 10.0).position_m, velocity * 10.0, atol=0.05)


def test_a_fix_a_beacon_spacing_away_is_an_outlier_and_the_track_keeps_going():
    state = start(0.0, np.zeros(3))
    for k in range(1, 6):
        state = update(state, 0.5 * k, np.array([0.4 * k, 0.0, 0.0])).state
    wrong = update(state, 3.0, np.array([2.4 + 1.2, 0.0, 0.0]))  # the neighbouring panel's ID
    assert not wrong.accepted
    np.testing.assert_allclose(wrong.state.position_m, [2.4, 0.0, 0.0], atol=0.02)
    assert update(wrong.state, 3.5, np.array([2.8, 0.0, 0.0])).accepted


def test_repeated_outliers_restart_the_track():
    rules = FilterRules(max_outliers=3)
    state = start(0.0, np.zeros(3), rules)
    for k in range(1, 4):
        state = update(state, 0.5 * k, np.zeros(3), rules).state
    steps = []
    for k in range(4, 7):
        step = update(state, 0.5 * k, np.array([5.0, 5.0, 0.0]), rules)
        steps.append(step)
        state = step.state
    assert [s.accepted for s in steps] == [False, False, True]
    assert steps[-1].restarted
    np.testing.assert_allclose(state.position_m, [5.0, 5.0, 0.0])


def test_bad_input_is_named():
    state = start(1.0, np.zeros(3))
    with pytest.raises(ValueError, match="fix_m"):
        update(state, 2.0, np.array([np.nan, 0, 0]))
    with pytest.raises(ValueError, match="t_s"):
        predict(state, 0.5)
