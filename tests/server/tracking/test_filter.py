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


def settled():
    """A track standing still at the origin: 1 s of 1 mm fixes at 20 per second (video)."""
    state = start(0.0, np.zeros(3))
    for k in range(1, 21):
        state = update(state, 0.05 * k, np.zeros(3), covariance_m2=np.eye(3) * 1e-6).state
    return state


def test_a_fix_with_a_large_covariance_moves_the_track_less():
    state = settled()
    fix = np.array([0.004, -0.002, 0.0])
    sure = update(state, 1.05, fix, covariance_m2=np.diag([1e-6, 1e-6, 4e-6])).state  # 1 mm: a near panel
    unsure = update(state, 1.05, fix, covariance_m2=np.diag([1e-4, 1e-4, 4e-4])).state  # 10 mm: gravity only
    assert np.linalg.norm(unsure.position_m) < 0.5 * np.linalg.norm(sure.position_m)
    assert np.linalg.norm(sure.position_m - fix) < 0.001
    # and the track knows it: its own position variance stays larger
    assert np.trace(unsure.covariance[:3, :3]) > np.trace(sure.covariance[:3, :3])


def test_a_fix_that_is_only_sure_along_one_axis_moves_the_track_along_the_other():
    state = settled()
    elongated = np.diag([1e-6, 1e-3, 1e-6])  # 1 mm in x, 32 mm in y
    after = update(state, 1.05, np.array([0.004, 0.004, 0.0]), covariance_m2=elongated).state
    assert after.position_m[0] > 0.003 and abs(after.position_m[1]) < 0.001


def test_without_a_covariance_the_rules_sigma_is_the_noise_and_a_floor_stays_under_a_tiny_one():
    state = settled()
    fix = np.array([0.004, 0.0, 0.0])
    plain = update(state, 1.05, fix).state
    as_rule = update(state, 1.05, fix, covariance_m2=np.eye(3) * (0.005**2 - 0.001**2)).state
    np.testing.assert_allclose(plain.position_m, as_rule.position_m, atol=1e-12)
    tiny = update(state, 1.05, fix, covariance_m2=np.zeros((3, 3))).state  # the floor: 1 mm per axis
    floor = update(state, 1.05, fix, FilterRules(fix_sigma_m=0.001)).state
    np.testing.assert_allclose(tiny.position_m, floor.position_m, atol=1e-12)
    with pytest.raises(ValueError, match="covariance_m2"):
        update(state, 1.05, fix, covariance_m2=np.full((3, 3), np.nan))


def test_the_gate_weighs_the_fix_by_its_covariance():
    state = settled()
    far = np.array([0.0, 0.3, 0.0])  # 30 cm off a still track
    assert not update(state, 1.05, far, covariance_m2=np.eye(3) * 1e-6).accepted
    assert update(state, 1.05, far, covariance_m2=np.eye(3) * 0.01).accepted  # 10 cm sigma: plausible
