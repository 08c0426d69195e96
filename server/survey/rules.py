"""The survey's tunables and the two ways it can end without a map."""

from __future__ import annotations

from dataclasses import dataclass

from server.pipeline import PipelineOptions
from server.rooms import RoomRules
from server.vision.beacons import CandidateRules
from server.vision.contour import BlobRules

# A survey frame looks up at up to ~30 degrees, so a panel far off the optical axis is seen up to
# ~60 degrees from its normal: a trapezoid that fills ~80 % of its bounding rectangle, sides up to
# ~0.6 : 1. Its panels are named by a person or by their stripes, not picked by their looks, so the
# looks are judged far more loosely than for a phone held face up (`BlobRules`' defaults).
SURVEY_BLOBS = BlobRules(min_rectangle_fill=0.7, min_aspect=0.5)


class SurveyInputError(ValueError):
    """The request itself is wrong (an unknown anchor, a label naming a beacon the sketch lacks):
    the CLI exits 2, the API answers 4xx; `field` is the part at fault."""

    def __init__(self, message: str, field: str | None = None):
        super().__init__(message)
        self.message = message
        self.field = field


class SurveyRefused(Exception):
    """Readable frames that cannot give the map (a panel not connected to the anchor, no frame
    with two panels): the CLI exits 1, the API answers 422; `beacon_id` names the panel at fault."""

    def __init__(self, message: str, beacon_id: int | None = None):
        super().__init__(message)
        self.message = message
        self.beacon_id = beacon_id


@dataclass(frozen=True)
class SurveyRules:
    # The image noise of a whole panel's points: its corners where the sub-pixel sides cross at the
    # mid level (before the pipeline takes its per-frame estimate of the clipped-edge growth off
    # them: that estimate, from the few pixels of the corner arcs, scatters by 0.1-0.3 px and grows
    # with the view's obliquity, which would shrink every oblique panel and stretch the map), and
    # the intersection of the corrected corners' diagonals, which the growth hardly moves. On
    # simulated office frames the mid-level sides fit a panel's true image grown by one distance to
    # 0.02 px, and the centre lies 0.01 px off (docs/survey.md). The residuals' variance scales the
    # covariance anyway, so only the ratios between these sigmas matter.
    corner_sigma_px: float = 0.05
    centre_sigma_px: float = 0.03
    # A panel cut by the frame border gives no corners of its own: its points are the corners and
    # centre of the outline fit's pose projected back, an extrapolation that leans on the fit's
    # gravity prior; they tie the panel in loosely and hardly move the whole panels' answer
    outline_sigma_px: float = 1.0
    # The phone's gravity sensor, when the frame's profile gives none (docs/contract.md)
    gravity_sigma_deg: float = 0.1
    # A panel on one frame whose points' RMS over their sigmas (after a first fit) is above this many
    # times the median of all sightings' marks a wrong label or a smeared panel: the sighting is left
    # out and the fit repeated (`run._without_outliers`)
    outlier_factor: float = 6.0
    # The compass error every frame of one survey shares (a building's steel deflects the field alike
    # over a room): the frames cannot measure it, so the bearing's sigma is never below it. Indoor phone
    # headings err by 10-20 degrees (docs/survey.md, the bearing); a room known to be clean may state less
    compass_bias_sigma_deg: float = 10.0
    max_evaluations: int = 200
    pipeline: PipelineOptions = PipelineOptions(blobs=SURVEY_BLOBS)
    room: RoomRules = RoomRules(candidates=CandidateRules(blobs=SURVEY_BLOBS))
