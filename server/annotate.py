"""A picture of what the pipeline saw in one frame (the paper's Fig. 8, with the numbers): PNG bytes.

The frame around the panels measured, upscaled so that one pixel is a block of several (the
sub-pixel sides and corners can be seen against the pixels), with, per panel:
- the region read at full resolution (grey-yellow) and the binarized blob's contour (cyan);
- the polygon stage's corners (small blue squares) and the sub-pixel sides (magenta lines), or
  the outline path's sub-pixel points (orange dots);
- the fix's corners (green discs, numbered in the contract's corner order) and the centre from
  the diagonals (red cross on the green diagonals);
and a caption: the beacon, position, reprojection error, ambiguity ratio, or the refusal's
reason and message, with a thumbnail of the whole frame showing where the enlarged part lies.
Drawn with OpenCV (sub-pixel lines through `shift`); Hershey fonts are ASCII only.
"""

from __future__ import annotations

import textwrap
from dataclasses import dataclass

import cv2
import numpy as np

from server.diagnostics import Diagnostics, PanelSight
from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal
from shared_schemas import FailureReason, LocateResult
from shared_schemas.cli import plural

# BGR colours; the corner colour is pure green so that tests (and eyes) can find the corners
CORNER = (0, 255, 0)
CENTRE = (0, 0, 255)
SIDE = (255, 0, 255)
CONTOUR = (255, 255, 0)
POLYGON = (255, 128, 0)
OUTLINE = (0, 165, 255)
REGION = (90, 200, 200)
REFUSED = (60, 60, 255)
TEXT = (235, 235, 235)
BAND = (32, 32, 32)

SHIFT = 4  # OpenCV's fractional bits: coordinates to 1/16 of a display pixel
DISPLAY_PX = 900  # the enlarged part's long side at most (and at least, for small parts, by whole-pixel blocks)
MAX_BLOCK = 24  # a frame pixel is at most this many display pixels wide
THUMBNAIL_PX = 200
CLOSE_UP_HALF_PX = 12  # frame pixels either side of a corner in its close-up
CLOSE_UP_BLOCK = 10.0  # display pixels per frame pixel there
FONT = cv2.FONT_HERSHEY_SIMPLEX
FONT_SCALE = 0.5
LINE_PX = 20
WRAP_CHARS = 100


@dataclass(frozen=True, eq=False)  # identity: holds numpy arrays
class FrameSeen:
    """What a picture needs of one frame, a small copy kept apart from the frame: the part around the
    panels measured (every `step`-th pixel when it is larger than the picture), the pixels around
    each corner of the result, a small copy of the whole frame, and the pipeline's sights."""

    size: tuple[int, int]  # the frame's width, height
    part: tuple[int, int, int, int]  # x0, y0, x1, y1 of the frame, enlarged in the picture
    part_pixels: np.ndarray  # pixels of `part`, every `step`-th row and column
    step: int
    close_ups: tuple[tuple[tuple[int, int, int, int], np.ndarray], ...]  # per corner: its box and its pixels
    thumbnail: np.ndarray | None  # the whole frame, every few pixels; None when `part` is the whole frame
    sights: tuple[PanelSight, ...]
    in_session: bool = False  # a device's session measured it (`server.locator.in_device_session`)

    @property
    def nbytes(self) -> int:
        arrays = [self.part_pixels, *(pixels for _, pixels in self.close_ups)]
        if self.thumbnail is not None:
            arrays.append(self.thumbnail)
        return sum(a.nbytes for a in arrays) + 2048 * (1 + len(self.sights))  # the sights' points, roughly


def annotate(frame: LumaFrame, diagnostics: Diagnostics, result: LocateResult, in_session: bool = False) -> bytes:
    """A PNG of `frame` with what the pipeline saw of each panel it measured (`diagnostics`, given
    to `server.locator.locate` in the pipeline's options) and `result` in a caption below."""
    return picture(seen_in(frame, diagnostics, result, in_session), result)


def seen_in(frame: LumaFrame, diagnostics: Diagnostics, result: LocateResult, in_session: bool = False) -> FrameSeen:
    """What a picture of `frame` needs, copied out of it (at most ~1 MB; strided copies: no resampling
    here, so that keeping it costs the locate path little)."""
    pixels, sights = frame.pixels, diagnostics.in_frame(frame.meta.full_offset)
    height, width = pixels.shape
    part = enlarged_part(sights, result, (width, height))
    x0, y0, x1, y1 = part
    step = max(1, int(1 / display_scale(x1 - x0, y1 - y0)))
    close_ups: tuple[tuple[tuple[int, int, int, int], np.ndarray], ...] = ()
    if result.corners_px is not None:
        boxes = [_close_up_box(x, y, width, height) for x, y in result.corners_px]
        close_ups = tuple((box, pixels[box[1] : box[3], box[0] : box[2]].copy()) for box in boxes)
    thumbnail = None
    if part != (0, 0, width, height):
        thumb_step = max(1, max(width, height) // THUMBNAIL_PX)
        thumbnail = pixels[::thumb_step, ::thumb_step].copy()
    return FrameSeen(
        size=(width, height),
        part=part,
        part_pixels=pixels[y0:y1:step, x0:x1:step].copy(),
        step=step,
        close_ups=close_ups,
        thumbnail=thumbnail,
        sights=tuple(sights),
        in_session=in_session,
    )


def picture(seen: FrameSeen, result: LocateResult) -> bytes:
    """The PNG of what `seen` kept, with `result` in a caption below."""
    sights = list(seen.sights)
    x0, y0, x1, y1 = seen.part
    scale = display_scale(x1 - x0, y1 - y0)
    image = _view(seen.part_pixels, seen.part, scale, sights, result, labels=True, in_session=seen.in_session)
    if seen.close_ups:
        image = _stacked(image, _corner_close_ups(seen.close_ups, sights, result))
    thumbnail = None if seen.thumbnail is None else _thumbnail(seen.thumbnail, seen.size, seen.part)
    image = _with_caption(image, _caption(result, sights, seen.part, scale), thumbnail)
    ok, png = cv2.imencode(".png", image)
    if not ok:  # pragma: no cover - OpenCV encodes any 8-bit BGR image
        raise RuntimeError("OpenCV could not encode the picture as PNG")
    return png.tobytes()


def _view(
    part_pixels: np.ndarray,
    part: tuple[int, int, int, int],
    scale: float,
    sights: list[PanelSight],
    result: LocateResult,
    labels: bool,
    in_session: bool = False,
) -> np.ndarray:
    """`part` (x0, y0, x1, y1) of the frame (its pixels, or every few of them) at `scale` display pixels
    per frame pixel, with the sights drawn."""
    x0, y0, x1, y1 = part
    size = (max(1, round((x1 - x0) * scale)), max(1, round((y1 - y0) * scale)))
    upscaled = size[0] >= part_pixels.shape[1]
    enlarged = cv2.resize(part_pixels, size, interpolation=cv2.INTER_NEAREST if upscaled else cv2.INTER_AREA)
    image = cv2.cvtColor(enlarged, cv2.COLOR_GRAY2BGR)

    def to_display(points: np.ndarray) -> np.ndarray:
        """Frame pixels (..., 2) to OpenCV's fixed-point display pixels."""
        return np.rint(display_px(points, part, scale) * (1 << SHIFT)).astype(np.int32)

    for sight in sights:
        _draw_sight(image, sight, to_display, _panel_name(sight, result, in_session) if labels else None)
    if not any(isinstance(s.outcome, Fix) for s in sights) and result.ok:  # a fix from no sight
        _draw_fix(image, result.corners_px, result.center_px, to_display, labels)
    return image


def _close_up_box(x: float, y: float, width: int, height: int) -> tuple[int, int, int, int]:
    """The frame pixels shown in the close-up of a corner at (x, y)."""
    cx, cy = int(round(x)), int(round(y))
    x0, y0 = min(max(0, cx - CLOSE_UP_HALF_PX), width - 1), min(max(0, cy - CLOSE_UP_HALF_PX), height - 1)
    return (
        x0,
        y0,
        min(width, max(cx + CLOSE_UP_HALF_PX + 1, x0 + 1)),
        min(height, max(cy + CLOSE_UP_HALF_PX + 1, y0 + 1)),
    )


def _corner_close_ups(
    close_ups: tuple[tuple[tuple[int, int, int, int], np.ndarray], ...], sights: list[PanelSight], result: LocateResult
) -> np.ndarray:
    """The result's four corners side by side, `CLOSE_UP_BLOCK` display pixels per frame pixel."""
    views = []
    for number, (box, pixels) in enumerate(close_ups):
        view = _view(pixels, box, CLOSE_UP_BLOCK, sights, result, labels=False)
        cv2.putText(view, f"corner {number}", (6, 18), FONT, FONT_SCALE, CORNER, 1, cv2.LINE_AA)
        views.append(cv2.copyMakeBorder(view, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=BAND))
    row_height = max(v.shape[0] for v in views)
    return np.hstack(
        [cv2.copyMakeBorder(v, 0, row_height - v.shape[0], 0, 0, cv2.BORDER_CONSTANT, value=BAND) for v in views]
    )


def _stacked(top: np.ndarray, bottom: np.ndarray) -> np.ndarray:
    """`top` above `bottom`, left-aligned on the band's colour."""
    width = max(top.shape[1], bottom.shape[1])
    canvas = np.full((top.shape[0] + bottom.shape[0], width, 3), BAND, dtype=np.uint8)
    canvas[: top.shape[0], : top.shape[1]] = top
    canvas[top.shape[0] :, : bottom.shape[1]] = bottom
    return canvas


def display_px(points: np.ndarray, part: tuple[int, int, int, int], scale: float) -> np.ndarray:
    """Frame pixels (..., 2), pixel centres at integers, to pixels of `part` enlarged by `scale`
    (a frame pixel is a block of `scale` display pixels: its centre is the block's)."""
    return (np.asarray(points, dtype=float) - part[:2] + 0.5) * scale - 0.5


def enlarged_part(sights: list[PanelSight], result: LocateResult, size: tuple[int, int]) -> tuple[int, int, int, int]:
    """x0, y0, x1, y1 of the frame to enlarge: every panel seen, with a margin; the whole frame if none."""
    boxes = []
    for sight in sights:
        if sight.roi_px is not None:
            boxes.append(np.array(sight.roi_px, dtype=float).reshape(2, 2))
        for points in (sight.contour_px, sight.outline_px):
            if points is not None and len(points):
                boxes.append(np.array([points.min(axis=0), points.max(axis=0)]))
    if not boxes and result.corners_px is not None:
        corners = np.asarray(result.corners_px)
        boxes.append(np.array([corners.min(axis=0), corners.max(axis=0)]))
    width, height = size
    if not boxes:
        return 0, 0, width, height
    low = np.min([box[0] for box in boxes], axis=0)
    high = np.max([box[1] for box in boxes], axis=0)
    margin = 0.15 * float(np.max(high - low)) + 8
    x0, y0 = (int(max(0, np.floor(v - margin))) for v in low)
    x1, y1 = int(min(width, np.ceil(high[0] + margin) + 1)), int(min(height, np.ceil(high[1] + margin) + 1))
    return x0, y0, max(x1, x0 + 1), max(y1, y0 + 1)


def display_scale(width: int, height: int) -> float:
    """Display pixels per frame pixel: whole blocks up to `DISPLAY_PX` for small parts, a reduction for large."""
    longest = max(width, height)
    if longest > DISPLAY_PX:
        return DISPLAY_PX / longest
    return float(max(1, min(MAX_BLOCK, DISPLAY_PX // longest)))


def _polyline(image: np.ndarray, points: np.ndarray, colour: tuple[int, int, int], closed: bool) -> None:
    cv2.polylines(image, [points.reshape(-1, 1, 2)], closed, colour, 1, cv2.LINE_AA, SHIFT)


def _panel_name(sight: PanelSight, result: LocateResult, in_session: bool) -> str:
    """What to call a panel: the result's beacon for the panel that gave the fix; in a device's session,
    where every panel is measured against one template beacon (`server.tracking.session`), the other
    panels are unnamed; elsewhere each sight's own beacon."""
    outcome = sight.outcome
    gave_fix = (
        isinstance(outcome, Fix)
        and outcome.center_px is not None
        and result.center_px is not None
        and float(np.hypot(*np.subtract(outcome.center_px, result.center_px))) < 0.5
    )
    if gave_fix:
        return f"beacon {result.beacon_id}"
    return "panel" if in_session else f"beacon {sight.beacon_id}"


def _draw_sight(image: np.ndarray, sight: PanelSight, to_display, name: str | None) -> None:
    """One panel's sight; `name`: its label, None for none (close-ups)."""
    if sight.roi_px is not None:
        corners = to_display(np.array(sight.roi_px, dtype=float).reshape(2, 2))
        cv2.rectangle(image, tuple(corners[0]), tuple(corners[1]), REGION, 1, cv2.LINE_AA, SHIFT)
    if sight.contour_px is not None:
        _polyline(image, to_display(sight.contour_px), CONTOUR, closed=True)
    if sight.polygon_px is not None:
        for corner in to_display(sight.polygon_px):
            half = 3 << SHIFT
            cv2.rectangle(image, tuple(corner - half), tuple(corner + half), POLYGON, 1, cv2.LINE_AA, SHIFT)
    if sight.sides_px is not None:
        for side in sight.sides_px:
            _polyline(image, to_display(side), SIDE, closed=False)
    if sight.outline_px is not None:
        for point in to_display(sight.outline_px):
            cv2.circle(image, tuple(point), 2 << SHIFT, OUTLINE, -1, cv2.LINE_AA, SHIFT)
    outcome = sight.outcome
    if isinstance(outcome, Fix):
        _draw_fix(image, outcome.corners_px, outcome.center_px, to_display, name is not None)
    if name is not None:
        _label_panel(image, sight, to_display, name)


def _draw_fix(image: np.ndarray, corners_px, center_px, to_display, labels: bool) -> None:
    """The corners, numbered in the contract's order, their diagonals and the centre (a round
    panel has no corners: its centre only)."""
    corners = None if corners_px is None else to_display(np.asarray(corners_px))
    if corners is not None:
        for a, b in ((0, 2), (1, 3)):
            cv2.line(image, tuple(corners[a]), tuple(corners[b]), (0, 140, 0), 1, cv2.LINE_AA, SHIFT)
    if center_px is not None:
        centre = tuple(to_display(np.asarray(center_px)))
        cv2.drawMarker(image, (centre[0] >> SHIFT, centre[1] >> SHIFT), CENTRE, cv2.MARKER_CROSS, 14, 2)
    if corners is None:
        return
    middle = corners.mean(axis=0)
    for number, corner in enumerate(corners):
        cv2.circle(image, tuple(corner), 5 << SHIFT, CORNER, -1, cv2.LINE_AA, SHIFT)
        if labels:  # the number outside the panel, away from its middle
            away = corner - middle
            away = away / max(float(np.hypot(*away)), 1.0) * (14 << SHIFT)
            x, y = (corner + away) / (1 << SHIFT)
            cv2.putText(image, str(number), (int(x) - 4, int(y) + 5), FONT, FONT_SCALE, CORNER, 1, cv2.LINE_AA)


def _panel_label(sight: PanelSight, name: str) -> str:
    """A panel's label: its name, and when refused the reason; a refusal that found no beacon, or none it could
    name, names none (the sight's beacon is only the template it was measured against)."""
    outcome = sight.outcome
    if isinstance(outcome, Fix):
        return name
    if outcome.reason is FailureReason.no_beacon:
        return outcome.reason.value
    if outcome.reason is FailureReason.unknown_beacon:
        return f"panel: {outcome.reason.value}"
    return f"{name}: {outcome.reason.value}"


def _label_panel(image: np.ndarray, sight: PanelSight, to_display, name: str) -> None:
    """The panel's label above it, or below it when the view has no room above (a panel at the frame's top
    edge), kept inside the view, on the band's colour so that it reads over a bright panel too."""
    points = [p for p in (sight.contour_px, sight.outline_px, sight.polygon_px) if p is not None and len(p)]
    if isinstance(sight.outcome, Fix) and sight.outcome.corners_px is not None:
        points.append(sight.outcome.corners_px)
    if not points:
        return
    shown = to_display(np.vstack(points)) >> SHIFT
    text = _ascii(_panel_label(sight, name))
    (width, height), below = cv2.getTextSize(text, FONT, FONT_SCALE, 1)
    x = min(max(2, int(shown[:, 0].min())), max(2, image.shape[1] - width - 2))
    y = int(shown[:, 1].min()) - 22  # clear of the corner numbers above the panel
    if y - height < 2:
        y = int(shown[:, 1].max()) + 22 + height
    y = min(max(y, height + 2), image.shape[0] - below - 2)
    cv2.rectangle(image, (x - 2, y - height - 2), (x + width + 2, y + below), BAND, -1)
    colour = CORNER if isinstance(sight.outcome, Fix) else REFUSED
    cv2.putText(image, text, (x, y), FONT, FONT_SCALE, colour, 1, cv2.LINE_AA)


def _ascii(text: str) -> str:
    return text.encode("ascii", "replace").decode("ascii")


Colour = tuple[int, int, int]
Line = list[tuple[str, Colour]]  # a caption line: its pieces of text, each in its colour


def _caption(
    result: LocateResult, sights: list[PanelSight], part: tuple[int, int, int, int], scale: float
) -> list[Line]:
    """The caption's lines."""
    texts: list[tuple[str, Colour]] = []
    if result.ok:
        assert result.position_m is not None  # outcomes.located sets it
        x, y, z = result.position_m
        source = f" ({result.beacon_id_source})" if result.beacon_id_source else ""
        texts.append((f"beacon {result.beacon_id}{source}   position x={x:+.4f} y={y:+.4f} z={z:+.4f} m", TEXT))
        quality = f"reprojection error {result.reprojection_error_px:.3g} px"
        if result.ambiguity_ratio is not None:
            quality += f"   ambiguity ratio {result.ambiguity_ratio:.3g}"
        if result.position_sigma_m is not None:
            quality += f"   sigma xy {1000 * max(result.position_sigma_m[:2]):.3g} mm"
        texts.append((quality, TEXT))
    else:
        texts.append((f"no fix: {result.reason}", REFUSED))
        texts.extend((line, REFUSED) for line in textwrap.wrap(result.message or "", WRAP_CHARS))
    for warning in result.warnings[:3]:
        texts.extend((line, TEXT) for line in textwrap.wrap(f"warning: {warning}", WRAP_CHARS))
    x0, y0, x1, y1 = part
    zoom = f"x{scale:.3g}" if scale != 1 else "not enlarged"
    panels = _panel_count(result, sights)
    close_ups = f", corners x{CLOSE_UP_BLOCK:g}" if result.corners_px is not None else ""
    texts.append((f"frame pixels x {x0}-{x1 - 1}, y {y0}-{y1 - 1}, {zoom}{close_ups}; {panels}", TEXT))
    thresholds = sorted({round(s.threshold_dn) for s in sights if s.threshold_dn is not None})
    fixed = result.corners_px is not None or any(isinstance(s.outcome, Fix) for s in sights)
    drawn = [  # the legend of what is in the picture
        (fixed, "corners 0-3 (contract order)", CORNER),
        (fixed, "centre (diagonals)", CENTRE),
        (any(s.sides_px is not None for s in sights), "sub-pixel sides", SIDE),
        (
            any(s.contour_px is not None for s in sights),
            "contour" + (f" (threshold {', '.join(map(str, thresholds))} DN)" if thresholds else " (coarse view)"),
            CONTOUR,
        ),
        (any(s.polygon_px is not None for s in sights), "polygon corners", POLYGON),
        (any(s.outline_px is not None for s in sights), "outline points", OUTLINE),
        (any(s.roi_px is not None for s in sights), "region read", REGION),
    ]
    return [[text] for text in texts] + _flowed([(label, colour) for shown, label, colour in drawn if shown])


def _panel_count(result: LocateResult, sights: list[PanelSight]) -> str:
    """How many panels the frame showed (the result's `beacons_in_view`, when the path counts them) and how many
    were measured (a sight that found no beacon measured none): a room refused for want of an ID saw its
    panels and measured none."""
    measured = sum(not (isinstance(s.outcome, Refusal) and s.outcome.reason is FailureReason.no_beacon) for s in sights)
    if result.beacons_in_view is None:
        return f"{plural(measured, 'panel')} measured"
    return f"{plural(result.beacons_in_view, 'panel')} in view, {measured} measured"


def _flowed(items: list[tuple[str, Colour]], width_px: int = 640) -> list[Line]:
    """Legend items on as few lines as fit in `width_px`, several to a line."""
    lines: list[Line] = [[]]
    used = 0
    for text, colour in items:
        wide = _text_width(text + "   ")
        if lines[-1] and used + wide > width_px:
            lines.append([])
            used = 0
        lines[-1].append((text + "   ", colour))
        used += wide
    return lines


def _text_width(text: str) -> int:
    return cv2.getTextSize(_ascii(text), FONT, FONT_SCALE, 1)[0][0]


def _thumbnail(small: np.ndarray, size: tuple[int, int], part: tuple[int, int, int, int]) -> np.ndarray:
    """The whole frame (`small`: every few of its pixels; `size`: its width, height), small, with the
    enlarged part outlined."""
    width, height = size
    scale = THUMBNAIL_PX / max(width, height)
    shown = cv2.resize(
        small, (max(1, round(width * scale)), max(1, round(height * scale))), interpolation=cv2.INTER_AREA
    )
    thumbnail = cv2.cvtColor(shown, cv2.COLOR_GRAY2BGR)
    x0, y0, x1, y1 = (round(v * scale) for v in part)
    cv2.rectangle(thumbnail, (x0, y0), (max(x1 - 1, x0 + 1), max(y1 - 1, y0 + 1)), REGION, 1)
    return thumbnail


def _with_caption(image: np.ndarray, lines: list[Line], thumbnail: np.ndarray | None) -> np.ndarray:
    """`image` above a dark band holding the caption's lines (left) and the thumbnail (right)."""
    text_width = max(sum(_text_width(text) for text, _ in line) for line in lines) + 20
    thumb_height, thumb_width = (0, 0) if thumbnail is None else thumbnail.shape[:2]
    width = max(image.shape[1], text_width + thumb_width + 10)
    band_height = max(len(lines) * LINE_PX + 12, thumb_height + 12)
    canvas = np.full((image.shape[0] + band_height, width, 3), BAND, dtype=np.uint8)
    canvas[: image.shape[0], : image.shape[1]] = image
    for row, line in enumerate(lines):
        baseline, left = image.shape[0] + 8 + (row + 1) * LINE_PX - 6, 10
        for text, colour in line:
            cv2.putText(canvas, _ascii(text), (left, baseline), FONT, FONT_SCALE, colour, 1, cv2.LINE_AA)
            left += _text_width(text)
    if thumbnail is not None:
        top, left = image.shape[0] + 6, width - thumb_width - 6
        canvas[top : top + thumb_height, left : left + thumb_width] = thumbnail
    return canvas
