"""What the one-panel pipeline saw of each panel it measured, kept only when asked (for pictures).

`PipelineOptions.diagnostics` is None on the normal path: the pipeline then keeps nothing beyond
its result. Given a `Diagnostics`, every call of `server.pipeline.locate_beacon` adds one
`PanelSight` to it, whichever path chose it (one panel, each panel of a room, a device's
session), so the caller of `server.locator.locate` sees every panel measured for its frame.

Pixels are in the *full frame* (the sensor frame a crop lies in, `FrameMeta.full_offset` added)
and as the frame shows them (distorted), pixel centres at integers: a room's crops and a
client's window land where they are in the frame the caller holds (`PanelSight.moved`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from server.outcomes import Fix, Refusal


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class PanelSight:
    """One panel as the pipeline measured it (full-frame pixels, distorted; any stage not reached is None).

    `roi_px`: x0, y0, x1, y1 of the region read at full resolution; `contour_px` (N, 2): the
    binarized blob's outer contour (`cut`: it touches the frame border); `polygon_px` (4, 2): the
    polygon stage's corners (cyclic, the contour's order); `sides_px` (4, K, 2): the sub-pixel
    sides as drawn lines, side k from corner k to corner k + 1 of the polygon's order;
    `outline_px` (M, 2): the outline path's sub-pixel points; `outcome`: the fix (corners in the
    contract's order, centre from the diagonals) or the refusal.
    """

    beacon_id: int
    outcome: Fix | Refusal
    roi_px: tuple[int, int, int, int] | None = None
    threshold_dn: float | None = None
    contour_px: np.ndarray | None = None
    cut: bool = False
    polygon_px: np.ndarray | None = None
    sides_px: np.ndarray | None = None
    outline_px: np.ndarray | None = None

    def moved(self, offset_px: tuple[float, float]) -> PanelSight:
        """The same sight with every pixel moved by `offset_px` (x, y)."""
        offset = np.asarray(offset_px, dtype=float)

        def move(points: np.ndarray | None) -> np.ndarray | None:
            return None if points is None else np.asarray(points, dtype=float) + offset

        roi = self.roi_px
        if roi is not None:
            dx, dy = int(round(offset[0])), int(round(offset[1]))
            roi = (roi[0] + dx, roi[1] + dy, roi[2] + dx, roi[3] + dy)
        outcome = self.outcome.shifted(offset_px) if isinstance(self.outcome, Fix) else self.outcome
        return replace(
            self,
            outcome=outcome,
            roi_px=roi,
            contour_px=move(self.contour_px),
            polygon_px=move(self.polygon_px),
            sides_px=move(self.sides_px),
            outline_px=move(self.outline_px),
        )


@dataclass(eq=False)  # identity: a request's own record, held by its (hashable) options
class Diagnostics:
    """The panels one request's pipeline measured, in the order it measured them (one thread: one request)."""

    panels: list[PanelSight] = field(default_factory=list)

    def add(self, sight: PanelSight) -> None:
        self.panels.append(sight)

    def in_frame(self, full_offset: tuple[int, int]) -> list[PanelSight]:
        """The sights in the pixels of a frame whose first pixel is `full_offset` of the full frame."""
        return [sight.moved((-full_offset[0], -full_offset[1])) for sight in self.panels]
