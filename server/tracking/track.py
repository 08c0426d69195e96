"""A device's motion track: the constant-velocity filter fed with fixes, and how far to trust it.

The filter (`server.tracking.filter`) smooths the fixes; on top of it the track counts the
fixes accepted in a row, because only a track that has just accepted a few fixes knows a
speed well enough to predict where the camera is (and so to carry a beacon ID over or to
veto one, `server.tracking.naming`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from server.tracking.filter import FilterRules, FilterState, predict, start, update
from shared_schemas import TrackState


@dataclass(frozen=True)
class TrackRules:
    motion: FilterRules = FilterRules()
    established_fixes: int = 2  # accepted fixes in a row (a speed) before the track may carry or veto an ID
    horizon_s: float = 2.4  # no prediction from a track silent for longer


@dataclass
class Track:
    rules: TrackRules = TrackRules()
    state: FilterState | None = None
    accepted_in_row: int = 0
    fixes: int = 0
    outliers: int = 0

    @property
    def established(self) -> bool:
        return self.state is not None and self.accepted_in_row >= self.rules.established_fixes

    def velocity_mps(self) -> np.ndarray:
        """The filtered velocity when the track is established, else zero (no trusted speed)."""
        return self.state.velocity_mps if self.established and self.state is not None else np.zeros(3)

    def predicted_m(self, t_s: float) -> np.ndarray | None:
        """Where an established, recent track puts the camera at `t_s`; None when it cannot tell (also
        before the track's time: a device whose clock went back, a replay, starts its track again)."""
        if not self.established or self.state is None or not 0 <= t_s - self.state.t_s <= self.rules.horizon_s:
            return None
        return predict(self.state, t_s, self.rules.motion).position_m

    def add(
        self, t_s: float, fix_m: np.ndarray, beacon_id_carried: bool = False, covariance_m2: np.ndarray | None = None
    ) -> TrackState:
        """Feed one fix (with its position covariance, `Fix.covariance_m2`, which weighs it);
        the filtered state, and whether the fix was an outlier."""
        self.fixes += 1
        outlier = False
        if self.state is None or t_s < self.state.t_s:
            self.state = start(t_s, fix_m, self.rules.motion, covariance_m2)
        else:
            step = update(self.state, t_s, fix_m, self.rules.motion, covariance_m2)
            self.state, outlier = step.state, not step.accepted
            self.outliers += int(outlier)
            if step.restarted:
                self.accepted_in_row = 0
        self.accepted_in_row = 0 if outlier else self.accepted_in_row + 1
        return TrackState(
            filtered_position_m=self.state.position_m.tolist(),
            velocity_mps=self.state.velocity_mps.tolist(),
            outlier=outlier,
            beacon_id_carried=beacon_id_carried,
        )

    def coasting(self, t_s: float) -> TrackState | None:
        """The track predicted to `t_s` for a capture without a fix (None before the first fix)."""
        if self.state is None or t_s < self.state.t_s:
            return None
        predicted = predict(self.state, t_s, self.rules.motion)
        return TrackState(
            filtered_position_m=predicted.position_m.tolist(),
            velocity_mps=predicted.velocity_mps.tolist(),
            outlier=False,
        )
