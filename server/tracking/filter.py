"""Constant-velocity Kalman filter over 3-D camera positions, with an outlier gate.

State (x, y, z, vx, vy, vz) in the map frame (m, m/s). The process noise is white
acceleration of `accel_sigma_mps2` (a walker turning a corner or stopping); the velocity gain
is capped so that the speed does not ring after a turn (see `update`); a fix whose
innovation exceeds the chi-square gate (3 dof) is an outlier: it is reported, not fused.
After `max_outliers` outliers in a row the track is restarted from the newest fix, since
then the track, not the fixes, is more likely wrong.

A fix's noise is its own position covariance when it has one (the pose fit's, `Fix.covariance_m2`:
a far or gravity-only fix weighs less than a near one), plus `min_fix_sigma_m` squared per axis
for what the fit does not see; without one, `fix_sigma_m` per axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class FilterRules:
    accel_sigma_mps2: float = 1.5
    fix_sigma_m: float = 0.005  # a fix without a covariance of its own
    # added to a fix's own covariance (per axis): what its fit does not see, such as the time
    # between the panel's rows and the frame's timestamp (at 1.5 m/s a millisecond is 1.5 mm)
    # or a real lens's calibration residual
    min_fix_sigma_m: float = 0.001
    initial_speed_sigma_mps: float = 1.0
    gate_chi2: float = 16.27  # chi-square, 3 dof, 99.9 %
    max_outliers: int = 3
    max_gap_s: float = 5.0  # a longer silence restarts the track


@dataclass(frozen=True)
class FilterState:
    t_s: float
    mean: np.ndarray  # (6,)
    covariance: np.ndarray  # (6, 6)
    outliers_in_row: int = 0

    @property
    def position_m(self) -> np.ndarray:
        return self.mean[:3]

    @property
    def velocity_mps(self) -> np.ndarray:
        return self.mean[3:]


@dataclass(frozen=True)
class FilterStep:
    state: FilterState
    accepted: bool
    restarted: bool
    mahalanobis2: float


_H = np.hstack([np.eye(3), np.zeros((3, 3))])


def fix_noise(covariance_m2: np.ndarray | None, rules: FilterRules = FilterRules()) -> np.ndarray:
    """Measurement noise (3, 3) of a fix: its own covariance plus the floor, else `fix_sigma_m`."""
    if covariance_m2 is None:
        return rules.fix_sigma_m**2 * np.eye(3)
    covariance = np.asarray(covariance_m2, float)
    if covariance.shape != (3, 3) or not np.all(np.isfinite(covariance)):
        raise ValueError(f"covariance_m2 must be 3 x 3 finite numbers, got {covariance_m2}")
    return 0.5 * (covariance + covariance.T) + rules.min_fix_sigma_m**2 * np.eye(3)


def start(
    t_s: float, fix_m: np.ndarray, rules: FilterRules = FilterRules(), covariance_m2: np.ndarray | None = None
) -> FilterState:
    covariance = np.zeros((6, 6))
    covariance[:3, :3] = fix_noise(covariance_m2, rules)
    covariance[3:, 3:] = rules.initial_speed_sigma_mps**2 * np.eye(3)
    return FilterState(float(t_s), np.concatenate([np.asarray(fix_m, float), np.zeros(3)]), covariance)


def predict(state: FilterState, t_s: float, rules: FilterRules = FilterRules()) -> FilterState:
    """The state at `t_s` (>= state.t_s) under constant velocity."""
    dt = float(t_s) - state.t_s
    if dt < 0:
        raise ValueError(f"t_s {t_s} is before the filter's time {state.t_s}")
    transition = np.eye(6)
    transition[:3, 3:] = dt * np.eye(3)
    q = rules.accel_sigma_mps2**2
    block = np.array([[dt**4 / 4, dt**3 / 2], [dt**3 / 2, dt**2]]) * q
    noise = np.kron(block, np.eye(3))
    return FilterState(
        float(t_s), transition @ state.mean, transition @ state.covariance @ transition.T + noise, state.outliers_in_row
    )


def update(
    state: FilterState,
    t_s: float,
    fix_m: np.ndarray,
    rules: FilterRules = FilterRules(),
    covariance_m2: np.ndarray | None = None,
) -> FilterStep:
    """Fuse one raw fix taken at `t_s` (with its position covariance, m^2, when it has one); gate
    it; restart after repeated outliers or a long gap."""
    fix = np.asarray(fix_m, float)
    if fix.shape != (3,) or not np.all(np.isfinite(fix)):
        raise ValueError(f"fix_m must be 3 finite numbers, got {fix_m}")
    noise = fix_noise(covariance_m2, rules)
    if t_s - state.t_s > rules.max_gap_s:
        return FilterStep(start(t_s, fix, rules, covariance_m2), True, True, 0.0)
    predicted = predict(state, t_s, rules)
    innovation = fix - _H @ predicted.mean
    s = _H @ predicted.covariance @ _H.T + noise
    d2 = float(innovation @ np.linalg.solve(s, innovation))
    if d2 > rules.gate_chi2:
        if predicted.outliers_in_row + 1 >= rules.max_outliers:
            return FilterStep(start(t_s, fix, rules, covariance_m2), True, True, d2)
        return FilterStep(
            FilterState(predicted.t_s, predicted.mean, predicted.covariance, predicted.outliers_in_row + 1),
            False,
            False,
            d2,
        )
    gain = predicted.covariance @ _H.T @ np.linalg.inv(s)
    # With fixes far more precise than a walker is predictable, the optimal velocity gain tends to
    # 2 / dt (an alpha-beta filter with beta -> 2): the speed then rings from step to step after a
    # turn. Capped at the position gain / dt (beta <= 1: the speed follows the fixes' differences);
    # the Joseph form keeps the covariance right for this gain.
    dt = max(predicted.t_s - state.t_s, 1e-3)
    cap = np.abs(np.diag(gain[:3])) / dt
    rows = np.abs(gain[3:]) > cap[:, None]
    gain[3:] = np.where(rows, np.sign(gain[3:]) * cap[:, None], gain[3:])
    mean = predicted.mean + gain @ innovation
    keep = np.eye(6) - gain @ _H
    covariance = keep @ predicted.covariance @ keep.T + gain @ noise @ gain.T
    return FilterStep(FilterState(predicted.t_s, mean, 0.5 * (covariance + covariance.T), 0), True, False, d2)
