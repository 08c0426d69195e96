"""All beacon candidates in a frame (the paper's office has four panels; `contour.py` keeps one).

Works on the same subsampled view as `roi.py` (`roi.coarse_view`, which keeps the frame's last
row and column, and the same step rule, `CoarseRules`), thresholded lower (at `level_fraction`
of the way from background to plateau) so that a short-exposure ID frame, whose panel is
striped between the LED's low and high levels, stays one blob. An LED that switches fully off
between chips leaves dark rows between the stripes: in an ID frame the mask is closed along the
columns over the longest dark run its code allows (`FrameView.stripe_gap_rows`, worked out from the
frame's metadata once, by `server.vlc.capture.frame_blobs`) before any shape is judged, so a comb of bars is one
blob again while two panels further apart than that run stay two. Every blob goes through the
shape rules of `contour.find_beacon_blob` on its own padded mask, judged against the look of
each panel the map has (`CandidateRules.looks`, `panel_looks`: a blob is a candidate when it
looks like any of them; none given: the paper's rounded square); blobs that touch the frame
border cannot be judged by their shape and are kept, flagged `cut_off` (the visible rows
still carry the ID, docs/vlc.md; the one-panel pipeline fits the visible outline).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, replace

import cv2
import numpy as np

from server.outcomes import Refusal
from server.vision.binarize import Levels
from server.vision.contour import Blob, BlobRules, PanelLook, convexity, find_beacon_blob
from server.vision.roi import CoarseRules, FrameView, coarse_levels, coarse_to_frame, coarse_view
from shared_schemas import Beacon


@dataclass(frozen=True)
class CandidateRules(CoarseRules):  # coarse_short_side_px, min_contrast_dn: shared with roi.RoiRules
    level_fraction: float = 0.2  # of plateau - background; below the LED's low level of 0.3
    close_px: int = 3  # bridges dark stripes and noise holes in the small view
    stripe_end_width: float = 0.5  # of a blob's widest row: its end cut by a dark stripe (`hidden_outline`)
    blobs: BlobRules = BlobRules()
    # how the map's panels look (`panel_looks`); a blob is a candidate if it looks like any of them.
    # Empty: the paper's rounded square (`PanelLook()`), which rejects round lamps and long strips.
    looks: tuple[PanelLook, ...] = ()

    def for_beacons(self, beacons: Iterable[Beacon]) -> CandidateRules:
        """These rules judging blobs by the looks of `beacons` (a map's), unless looks are set already."""
        return self if self.looks else replace(self, looks=panel_looks(beacons))


def panel_looks(beacons: Iterable[Beacon]) -> tuple[PanelLook, ...]:
    """The distinct looks (outline fill and aspect) of `beacons`, in their order."""
    looks: list[PanelLook] = []
    for beacon in beacons:
        look = PanelLook.of(beacon)
        rounded = PanelLook(fill=round(look.fill, 3), aspect=round(look.aspect, 3))
        if rounded not in looks:
            looks.append(rounded)
    return tuple(looks)


@dataclass(frozen=True, eq=False)  # identity: blobs hold numpy arrays
class BeaconBlob:
    """One candidate panel, in full-frame pixels."""

    contour_px: np.ndarray  # (N, 2) float, outer contour (coarse: `step` px resolution)
    bounding_box: tuple[int, int, int, int]  # x, y, width, height
    centroid_px: tuple[float, float]
    area_px: float
    cut_off: bool
    # ID frames of an LED that switches (almost) off between chips: the outline runs partly through dark
    # rows (a corner between two stripes, or the panel beyond its first or last stripe), unseen there; its
    # shape was judged only by its convexity, as a cut panel's
    hidden_outline: bool = False


@dataclass(frozen=True)
class Candidates:
    blobs: tuple[BeaconBlob, ...]  # largest first
    levels: Levels
    step: int
    rejected: tuple[str, ...]  # why other bright blobs are not beacons
    origin: tuple[int, int] = (0, 0)  # the coarse view's first (column, row) in the frame (`roi.FrameView.grid`)
    stripe_gap_rows: int = 0  # the frame's dark rows bridged (`FrameView.stripe_gap_rows`): `blob_mask` bridges alike


def _centroid_px(
    inside: np.ndarray, x: int, y: int, step: int, shape: tuple[int, int], origin: tuple[int, int]
) -> tuple[float, float]:
    """Mean frame position (x, y) of the view pixels `inside` (bool, the blob's box at view pixel x, y)."""
    rows, columns = np.nonzero(inside)
    centre = coarse_to_frame(np.column_stack([columns + x, rows + y]), step, shape, origin).mean(axis=0)
    return float(centre[0]), float(centre[1])


def _closed(mask: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """`mask` closed by `kernel`, seeing dark beyond the image's border (OpenCV's default border
    counts the outside as lit in the erosion: a blob near the border would be joined to it)."""
    pad_y, pad_x = kernel.shape[0] // 2, kernel.shape[1] // 2
    padded = cv2.copyMakeBorder(mask, pad_y, pad_y, pad_x, pad_x, cv2.BORDER_CONSTANT, value=0)
    closed = cv2.morphologyEx(padded, cv2.MORPH_CLOSE, kernel)
    return np.ascontiguousarray(closed[pad_y : closed.shape[0] - pad_y, pad_x : closed.shape[1] - pad_x])


def _row_runs(a: np.ndarray, length: int, op: np.ufunc) -> np.ndarray:
    """`op` (np.bitwise_or, np.bitwise_and) of every `length` consecutive rows of `a`: row i of the result is that
    of rows i .. i + length - 1 (len(a) - length + 1 rows), by doubling spans (log2(length) passes, not length)."""
    span = 1
    while 2 * span <= length:
        a = op(a[:-span], a[span:])
        span *= 2
    return a if span == length else op(a[: len(a) - (length - span)], a[length - span :])


def _closed_columns(mask: np.ndarray, half: int) -> np.ndarray:
    """`_closed(mask, np.ones((2 * half + 1, 1), np.uint8))`, the same pixels: a vertical line's closing as a
    running maximum then minimum over the rows, each row's pixels packed 8 to a byte (OpenCV's cost grows with the
    line's length: a 1 m ID frame's 161 rows, 2-6 ms on a panel's box, against 0.2 ms here)."""
    height, width = mask.shape
    bits = np.packbits(mask, axis=1)  # lit: 1
    padded = np.zeros((height + 4 * half, bits.shape[1]), np.uint8)  # dark beyond the border, as `_closed` sees it
    padded[2 * half : 2 * half + height] = bits
    dilated = _row_runs(padded, 2 * half + 1, np.bitwise_or)  # rows -half .. height + half - 1
    closed = np.unpackbits(_row_runs(dilated, 2 * half + 1, np.bitwise_and), axis=1, count=width)
    return np.multiply(closed, 255, out=closed)


MAX_COMPONENTS_OWN_STATS = 4  # beyond (a noisy frame's many specks): OpenCV's own statistics


def _components(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """`cv2.connectedComponentsWithStats(mask, connectivity=8)` without the centroids: (count, labels, stats),
    the same numbers for every component but the background (row 0 left zero below `MAX_COMPONENTS_OWN_STATS`).

    OpenCV's statistics cost 15-20x its labelling (12 vs 0.7 ms on a panel's 760 x 760 box); a mask of a
    few components (a panel's, a frame's few lamps) gets them from each component's own pixels.
    """
    count, labels = cv2.connectedComponents(mask, connectivity=8)
    if count - 1 > MAX_COMPONENTS_OWN_STATS:
        count, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        return count, labels, stats
    stats = np.zeros((count, 5), np.int32)
    for label in range(1, count):
        own = mask if count == 2 else (labels == label).view(np.uint8)  # one component: all of the mask
        x, y, w, h = cv2.boundingRect(own)
        stats[label] = x, y, w, h, cv2.countNonZero(own[y : y + h, x : x + w])
    return count, labels, stats


def _centroid(labels: np.ndarray, label: int, area: int) -> np.ndarray:
    """(x, y) of component `label`: OpenCV's centroid, the integer sum of its coordinates over its area."""
    rows, columns = np.nonzero(labels == label)
    return np.array([int(columns.sum()) / area, int(rows.sum()) / area])


def candidate_level(levels: Levels, rules: CandidateRules) -> float:
    """The candidate threshold: `level_fraction` of the way from the background to the plateau."""
    return levels.background + rules.level_fraction * levels.contrast


def candidate_mask(
    image: np.ndarray, levels: Levels, rules: CandidateRules, step: int = 1, stripe_gap_rows: int = 0
) -> np.ndarray:
    """Binary mask (uint8 0 / 255) of pixels above the candidate level, small gaps closed; `image`
    holds every `step`-th frame row and column.

    The closings see dark beyond the image's border, so a panel within `close_px` of the border
    is not joined to it and flagged cut off (`close_px` * step frame pixels). With
    `stripe_gap_rows` = g (`FrameView.stripe_gap_rows`), dark rows between stripes are bridged along the columns
    (`_bridged`) over gaps up to ceil(g / step) view rows (a gap of g frame rows holds at most that
    many sampled rows), one view row more when that is odd; wider gaps stay open.
    """
    _, mask = cv2.threshold(image, candidate_level(levels, rules), 255, cv2.THRESH_BINARY)
    if stripe_gap_rows > 0:  # first: the closing below could join two stripes by a thread of noise
        mask = _bridged(mask, int(np.ceil(stripe_gap_rows / step)))
    if rules.close_px > 0:
        mask = _closed(mask, np.ones((2 * rules.close_px + 1, 2 * rules.close_px + 1), np.uint8))
    return mask


def _bridged(mask: np.ndarray, gap_rows: int) -> np.ndarray:
    """`mask` (uint8 0 / 255) with the dark rows between stripes filled where they span at most
    `gap_rows` rows: blobs joined by a vertical closing are one panel, and each run of dark rows
    inside one is filled by the quadrilateral between the lit rows above and below it. A dark row
    carries no edge: the panel's width there is the neighbouring lit rows' (a closing alone would
    keep the narrower of the two and notch a panel turned to the rows at every dark stripe)."""
    half = (gap_rows + 1) // 2  # a vertical line of 2 * half + 1 rows closes gaps up to 2 * half rows
    joined = _closed_columns(mask, half)
    # a stripe's blurred end (an exposure's smear, shorter than a chip) lies within a quarter of the run:
    # its widest row there, not the first row above the threshold, gives the panel's width
    reach = max(1, gap_rows // 4)
    count, labels, stats = _components(joined)
    for label in range(1, count):
        x, y, w, h, _ = stats[label]
        own = mask[y : y + h, x : x + w] > 0  # one component holds all of the mask (a closing only adds)
        if count > 2:
            own &= labels[y : y + h, x : x + w] == label
        lit = own.any(axis=1)
        first = np.where(lit, np.argmax(own, axis=1), w)
        # numpy's argmax along reversed rows is ~10x its argmax along contiguous ones: a flipped copy instead
        last = np.where(lit, w - 1 - np.argmax(cv2.flip(own.view(np.uint8), 1), axis=1), -1)
        rows = np.flatnonzero(lit)
        for gap in np.flatnonzero(np.diff(rows) > 1):  # the component joins them: a gap of <= 2 * half rows
            above = rows[(rows <= rows[gap]) & (rows > rows[gap] - reach)]
            below = rows[(rows >= rows[gap + 1]) & (rows < rows[gap + 1] + reach)]
            a, b = above[np.argmax(last[above] - first[above])], below[np.argmax(last[below] - first[below])]
            corners = [[first[a], a], [last[a], a], [last[b], b], [first[b], b]]
            cv2.fillConvexPoly(joined, np.array(corners, np.int32) + [x, y], 255)
    return joined


def find_beacon_blobs(
    pixels: np.ndarray, rules: CandidateRules = CandidateRules(), view: FrameView = FrameView()
) -> Candidates:
    """Every beacon-shaped blob of a frame (height, width) uint8, largest first; `view` places a window and
    says how many dark rows an ID frame's stripes may leave between them (`FrameView.stripe_gap_rows`)."""
    if pixels.ndim != 2 or pixels.dtype != np.uint8:
        raise ValueError(f"pixels must be a 2-D uint8 luma image, got {pixels.dtype} {pixels.shape}")
    step, origin = view.grid(pixels.shape, rules)
    gap = view.stripe_gap_rows
    small = coarse_view(pixels, step, origin)  # to the frame's last row and column: `cut_off` is tested on it
    levels = view.levels or coarse_levels(small)
    if levels.contrast < rules.min_contrast_dn:
        return Candidates((), levels, step, ("nothing stands out of the background",), origin, gap)
    mask = candidate_mask(small, levels, rules, step, gap)
    level = candidate_level(levels, rules)
    shape_rules = replace(rules.blobs, min_area_px=rules.blobs.min_area_px / step**2)
    looks = rules.looks or (PanelLook(),)
    count, labels, stats = _components(mask)
    blobs: list[BeaconBlob] = []
    rejected: list[str] = []
    for label in range(1, count):
        x, y, w, h, area = stats[label]
        if area < rules.blobs.min_area_px / step**2:
            continue
        # the component alone, padded so that the shape rules never see the frame border
        alone = np.zeros((h + 4, w + 4), np.uint8)
        alone[2:-2, 2:-2] = np.where(labels[y : y + h, x : x + w] == label, 255, 0)
        found = _judged(alone, shape_rules, looks)
        cut_off = x <= 0 or y <= 0 or x + w >= small.shape[1] or y + h >= small.shape[0]
        hidden_outline = False
        # back to frame pixels: the view's last column and row are the frame's, closer than `step`
        x0, y0 = coarse_to_frame(np.array([x, y]), step, pixels.shape, origin).astype(int)
        x1 = min(pixels.shape[1], origin[0] + (x + w) * step)
        y1 = min(pixels.shape[0], origin[1] + (y + h) * step)
        contour_px: np.ndarray | None = None
        if isinstance(found, Refusal):
            # a cut panel's shape cannot be judged: keep it, flagged; only an ID frame's (`stripe_gap_rows`)
            # may be a striped panel whose outline runs through dark rows, cut there as by a border
            striped = gap > 0 and not cut_off
            if not (cut_off or striped):
                rejected.append(found.message)
                continue
            contour = cv2.findContours(alone, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)[0][0].reshape(-1, 2)
            if striped:
                lit = (small[y : y + h, x : x + w] > level) & (labels[y : y + h, x : x + w] == label)
                hidden_outline = _striped_cut(lit, contour, rules, step, gap)
                if not hidden_outline and step > 1:
                    contour_px = _fine_striped_outline(pixels, (x0, y0, x1, y1), levels, rules, step, gap)
                    hidden_outline = contour_px is not None
                if not hidden_outline:
                    rejected.append(found.message)
                    continue
        else:
            contour = found.contour
        if contour_px is None:
            contour_px = coarse_to_frame(contour.astype(float) - 2 + [x, y], step, pixels.shape, origin)
        blobs.append(
            BeaconBlob(
                contour_px=contour_px,
                bounding_box=(int(x0), int(y0), int(x1 - x0), int(y1 - y0)),
                centroid_px=_centroid_px(labels[y : y + h, x : x + w] == label, x, y, step, pixels.shape, origin),
                area_px=float(area * step**2),
                cut_off=bool(cut_off),
                hidden_outline=hidden_outline,
            )
        )
    blobs.sort(key=lambda b: b.area_px, reverse=True)
    return Candidates(tuple(blobs), levels, step, tuple(rejected), origin, gap)


def _striped_cut(lit: np.ndarray, contour: np.ndarray, rules: CandidateRules, step: int, stripe_gap_rows: int) -> bool:
    """Whether a blob refused by its shape may be a striped panel whose outline runs partly through dark
    rows (`BeaconBlob.hidden_outline`): an ID frame's (`stripe_gap_rows`), convex, and either dark rows
    inside it (`lit`: its pixels above the level before any closing; the LED's low level is below it, so a
    corner of the panel between two stripes is unseen) or its top or bottom end flat, at least
    `stripe_end_width` of its widest row within a quarter of the dark run (the rest of the panel beyond a
    stripe's end: a whole panel ends in a corner or a rounded edge unless it is level with the rows, and
    then it passes the shape rules)."""
    if stripe_gap_rows <= 0 or convexity(contour, cv2.contourArea(contour)) < rules.blobs.min_convexity:
        return False
    rows = np.flatnonzero(lit.any(axis=1))
    if len(rows) == 0:
        return False
    if np.any(np.diff(rows) > 1):
        return True
    first = np.argmax(lit[rows], axis=1)
    width = lit.shape[1] - np.argmax(lit[rows, ::-1], axis=1) - first
    reach = max(1, int(np.ceil(stripe_gap_rows / step / 4)))
    return bool(max(width[:reach].max(), width[-reach:].max()) >= rules.stripe_end_width * width.max())


def _fine_striped_outline(
    pixels: np.ndarray,
    box: tuple[int, int, int, int],
    levels: Levels,
    rules: CandidateRules,
    step: int,
    stripe_gap_rows: int,
) -> np.ndarray | None:
    """The outline (N, 2, frame pixels) of a striped blob refused in the coarse view, when on the frame's
    own rows over its box (`box`: x0, y0, x1, y1) it is a striped panel cut by its dark rows (`_striped_cut`),
    else None. The view keeps every `step`-th row: where the stripes' period is a few steps (a 1-4 kHz LED
    at ~21 us a row: 12-48 rows, at step 9) each kept row falls somewhere on a bar's exposure-smeared
    edge or on its middle, so the blob's rows are as wide as their phase in the bar, not as the panel,
    and a small blob's outline steps by a view pixel a row (lab11's photos: 0.75-0.91 of its hull)."""
    height, width = pixels.shape
    margin = stripe_gap_rows + 2 * step  # the bridge may reach that far beyond the view's box
    x0, y0 = max(0, box[0] - margin), max(0, box[1] - margin)
    x1, y1 = min(width, box[2] + margin), min(height, box[3] + margin)
    crop = np.ascontiguousarray(pixels[y0:y1, x0:x1])
    fine_rules = _fine_rules(rules)
    mask = candidate_mask(crop, levels, fine_rules, 1, stripe_gap_rows)
    count, labels, stats = _components(mask)
    if count <= 1:
        return None
    label = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    x, y, w, h, _ = stats[label]
    if x <= 0 or y <= 0 or x + w >= crop.shape[1] or y + h >= crop.shape[0]:
        return None  # it reaches beyond the box's margin: not the blob judged in the view
    alone = np.zeros((h + 4, w + 4), np.uint8)
    alone[2:-2, 2:-2] = np.where(labels[y : y + h, x : x + w] == label, 255, 0)
    contour = cv2.findContours(alone, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_NONE)[0][0].reshape(-1, 2)
    lit = (crop[y : y + h, x : x + w] > candidate_level(levels, rules)) & (labels[y : y + h, x : x + w] == label)
    if not _striped_cut(lit, contour, fine_rules, 1, stripe_gap_rows):
        return None
    return contour.astype(float) - 2 + [x + x0, y + y0]


def _fine_rules(rules: CandidateRules) -> CandidateRules:
    """`rules` for a mask on the frame's own pixels (`blob_mask`): its level, a 1-pixel closing."""
    return replace(rules, close_px=1)


_PREFIX = "the brightest blob is not the beacon: "  # contour.find_beacon_blob's, said once


def _judged(alone: np.ndarray, rules: BlobRules, looks: tuple[PanelLook, ...]) -> Blob | Refusal:
    """The blob of `alone` if it looks like any of `looks`, else the refusal of the first look
    (the others' reasons appended when the map has several)."""
    refusals: list[Refusal] = []
    for look in looks:
        found = find_beacon_blob(alone, rules, look)
        if not isinstance(found, Refusal):
            return found
        refusals.append(found)
    if len(refusals) == 1:
        return refusals[0]
    reasons = "; ".join(dict.fromkeys(r.message.removeprefix(_PREFIX) for r in refusals))
    return replace(refusals[0], message=f"{_PREFIX}it looks like none of the map's {len(looks)} panels ({reasons})")


def blob_mask(
    pixels: np.ndarray,
    blob: BeaconBlob,
    found: Candidates,
    rules: CandidateRules = CandidateRules(),
    margin_px: int = 4,
) -> tuple[int, int, np.ndarray]:
    """(y0, x0, mask): the full-resolution mask (bool) of `blob`, one of `found`, over its box plus `margin_px`,
    at `found`'s levels and bridging the dark rows its blobs were found with (`Candidates.stripe_gap_rows`).

    Only the connected component nearest the blob's centroid is kept, so a neighbouring
    panel inside the box does not leak in.
    """
    x, y, w, h = blob.bounding_box
    height, width = pixels.shape
    x0, y0 = max(0, x - margin_px), max(0, y - margin_px)
    x1, y1 = min(width, x + w + margin_px + 1), min(height, y + h + margin_px + 1)
    window = np.ascontiguousarray(pixels[y0:y1, x0:x1])
    mask = candidate_mask(window, found.levels, _fine_rules(rules), 1, found.stripe_gap_rows)
    count, labels, stats = _components(mask)
    if count <= 1:
        return y0, x0, np.zeros(mask.shape, bool)
    target = np.array(blob.centroid_px) - [x0, y0]
    largest = 1 + np.argsort(stats[1:, cv2.CC_STAT_AREA])[::-1][:3]
    areas = stats[:, cv2.CC_STAT_AREA]
    if len(largest) == 1:
        return y0, x0, labels == largest[0]
    best = min(largest, key=lambda k: float(np.hypot(*(_centroid(labels, k, int(areas[k])) - target))))
    return y0, x0, labels == best
