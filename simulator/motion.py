"""The camera moving during one frame's exposure and readout (issue 13, item 1): hand tremor, walking.

`MotionSpec` is the knob (`ChainSpec.motion`): random linear and angular velocities, drawn per frame
(`draw_velocities`) from the frame's generator, constant over the frame (its 10 ms exposure and 30 ms
readout are short against a step, 0.5 s, and a third of a 10 Hz tremor's period: the constant rate
is a first-order model). The renderer turns them into a `simulator.render.ReadoutMotion`: each row
seen from where the camera is while that row is exposed (the rolling shutter skews the outline) and
the light averaged over the row's exposure (motion blur, `render.exposure_polygons_px`).

Velocities are in the map frame (x, y horizontal, z up), as `ReadoutMotion` and `PoseSpec` have them.
Presets and where their numbers come from: `MotionSpec.tremor`, `MotionSpec.walking`
(docs/simulator.md, "Phone image chain").
"""

from __future__ import annotations

import numpy as np
from pydantic import Field

from shared_schemas.models import Strict


class MotionSpec(Strict):
    """How the phone moves while a frame is taken; all zero (the default) = held still."""

    speed_mps: float = Field(default=0.0, ge=0, le=10,
                             description="a steady horizontal velocity of this size in a random direction (walking)")
    velocity_rms_mps: float = Field(default=0.0, ge=0, le=10,
                                    description="random velocity, RMS per map axis (tremor; a walker's bob and sway)")
    angular_rate_rms_dps: float = Field(default=0.0, ge=0, le=500,
                                        description="random angular velocity, RMS per map axis (a random axis)")

    @property
    def still(self) -> bool:
        return self.speed_mps == 0 and self.velocity_rms_mps == 0 and self.angular_rate_rms_dps == 0

    @classmethod
    def tremor(cls) -> MotionSpec:
        """A phone held still by hand: physiological tremor and sway.

        1 deg/s per axis: the photographers' reciprocal rule (hand-held exposures up to 1 / f, f the
        35 mm equivalent focal length in mm, stay sharp to the 0.03 mm circle of confusion of 35 mm
        film; Wikipedia "Camera shake") allows a turn rate of 0.03 mm / (f x 1 / f) = 0.03 rad/s =
        1.7 deg/s for most shots, so ~1 deg/s per axis RMS (1.4 deg/s across the two axes that move
        the image). 5 mm/s per axis: a 0.1 mm tremor at 8 Hz (2 pi x 8 Hz x 0.1 mm); an assumption,
        and at 1 m it moves the image 15x less than the turn. Not measured on a Mi 8.
        """
        return cls(velocity_rms_mps=0.005, angular_rate_rms_dps=1.0)

    @classmethod
    def walking(cls) -> MotionSpec:
        """A phone held in front of a walker.

        1.2 m/s horizontally: people walk at 1.2-1.4 m/s (preferred walking speed, ~1.4 m/s;
        Wikipedia "Preferred walking speed"), the lower end while looking at a phone. 0.1 m/s per axis:
        the step's bob (about +-2.5 cm at 2 steps/s, 0.2 m/s RMS vertically at the hips) damped by
        the arm; an assumption. 10 deg/s per axis: a hand-held phone's gyroscope rates while filming
        stay within about +-0.5 rad/s (+-29 deg/s; Karpenko et al., "Digital Video Stabilization and
        Rolling Shutter Correction using Gyroscopes", Stanford CSTR 2011-03, Fig. 1c), about 3 sigma.
        """
        return cls(speed_mps=1.2, velocity_rms_mps=0.1, angular_rate_rms_dps=10.0)


def draw_velocities(spec: MotionSpec, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """(velocity m/s (3,), angular velocity deg/s (3,)) of one frame, map frame; a still spec draws
    nothing from `rng` (so that still frames stay what they were)."""
    if spec.still:
        return np.zeros(3), np.zeros(3)
    heading = rng.uniform(0.0, 2 * np.pi)
    velocity = spec.speed_mps * np.array([np.cos(heading), np.sin(heading), 0.0])
    velocity = velocity + spec.velocity_rms_mps * rng.standard_normal(3)
    return velocity, spec.angular_rate_rms_dps * rng.standard_normal(3)
