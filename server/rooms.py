"""Rooms with many beacons: one fix per panel in view, the best chosen, agreeing ones fused.

`server.pipeline.locate` handles one panel. Here every blob of the frame that looks like one
of the map's panels (`server.vision.beacons`, any shape) and has an ID gets its own crop (the
other panels blanked to the background level, the principal point shifted, so OpenCV's
distortion model stays exact) and its own `locate`; a panel cut by the frame border too (the
pipeline fits its visible outline). The fix of the largest panel in view is the best
conditioned (the error of a panel's pose grows with distance over its visible image size); the
other fixes are averaged in, weighted by that same measure, only when they agree with it
within `fuse_gate_m` (a panel with a wrong ID would move the fix by a beacon spacing, so it is
left out, and said).

`locate_in_room` serves a multi-beacon map without a given ID and without a device session
(`server.locator` chooses): it reads the frame's own stripes (a short-exposure frame,
docs/vlc.md), names each panel by them (`read_room`; a cut panel from the rows still in view),
and measures the named panels on the frame with their stripes flattened by their codes; a
device's session (`server.tracking`) instead brings IDs read from the ID frames beside a pose
frame, and uses `locate_panel` and `choose_and_fuse` from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal, located, refused
from server.pipeline import PipelineOptions, locate_beacon
from server.vision.beacons import BeaconBlob, CandidateRules, Candidates, blob_mask
from server.vision.binarize import Levels
from server.vlc.capture import frame_blobs
from server.vlc.codec import DATA_BITS, MESSAGE_CHIPS
from server.vlc.decoder import IdEvidence, StripeRules, row_time_s
from server.vlc.flatten import FlattenRules, flatten_stripes
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, Crop, FailureReason, LocateResult, VlcReading


@dataclass(frozen=True)
class RoomRules:
    crop_margin_px: int = 48
    fuse_gate_m: float = 0.03
    fuse: bool = True
    candidates: CandidateRules = CandidateRules()
    stripes: StripeRules = StripeRules()
    flatten: FlattenRules = FlattenRules()
    # A panel cut by the frame border is named like a whole one, by the decoder's own confidence,
    # but never from fewer visible rows than span the message's data part (16 of its 21 chips):
    # with less, some of the ID's 8 bits were not seen. From 20 chips (all but the one BMC restores)
    # one frame holds the whole ID; between the two the decoder names it only when the unseen chips
    # are the header's.
    min_cut_chips: float = 2 * DATA_BITS


@dataclass(frozen=True, eq=False)  # identity: fixes hold numpy arrays
class PanelFix:
    """A fix from one panel of the frame, with the blob it came from and the ID reading that named it."""

    blob: BeaconBlob
    beacon: Beacon
    fix: Fix
    vlc: VlcReading | None = None


def crop_frame(
    frame: LumaFrame, blob: BeaconBlob, others: list[BeaconBlob], margin_px: int, levels: Levels
) -> tuple[LumaFrame, tuple[int, int]]:
    """`frame` cut to `blob`'s box plus a margin, other blobs blanked; and (x0, y0).

    The crop keeps its place in the sensor frame and the frame's levels (its `crop` block), so
    the one-panel pipeline reads it on the full frame's coarse grid with the full frame's levels:
    a client's window of the frame gives the same crop and the same answer (docs/contract.md,
    "Windows").
    """
    height, width = frame.pixels.shape
    x, y, w, h = blob.bounding_box
    x0, y0 = max(0, x - margin_px), max(0, y - margin_px)
    x1, y1 = min(width, x + w + margin_px), min(height, y + h + margin_px)
    pixels = np.array(frame.pixels[y0:y1, x0:x1])
    for other in others:
        ox, oy, ow, oh = other.bounding_box
        pad = 16
        ax0, ay0 = max(ox - pad - x0, 0), max(oy - pad - y0, 0)
        ax1, ay1 = min(ox + ow + pad - x0, x1 - x0), min(oy + oh + pad - y0, y1 - y0)
        if ax1 > ax0 and ay1 > ay0:
            pixels[ay0:ay1, ax0:ax1] = np.uint8(round(levels.background))
    pixels.flags.writeable = False
    (full_width, full_height), (column, row) = frame.meta.full_size, frame.meta.full_offset
    crop = Crop(
        x=column + x0,
        y=row + y0,
        full_width=full_width,
        full_height=full_height,
        levels_dn=[levels.background, levels.plateau],
    )
    # the meta keeps the full frame's camera (the contract's), the frame the crop's own
    meta = frame.meta.model_copy(update={"width": x1 - x0, "height": y1 - y0, "row_stride": None, "crop": crop})
    camera = frame.camera.model_copy(update={"cx": frame.camera.cx - x0, "cy": frame.camera.cy - y0})
    return LumaFrame(pixels=pixels, meta=meta, camera=camera), (x0, y0)


def locate_panel(
    frame: LumaFrame,
    blob: BeaconBlob,
    others: list[BeaconBlob],
    beacon: Beacon,
    id_source: BeaconIdSource,
    options: PipelineOptions,
    levels: Levels,
    rules: RoomRules = RoomRules(),
) -> Fix | Refusal:
    """The one-panel pipeline on `blob` alone as map beacon `beacon` (`levels`: the frame's); pixels in the frame."""
    crop, offset = crop_frame(frame, blob, others, rules.crop_margin_px, levels)
    fix = locate_beacon(crop, beacon, options, id_source)
    return fix if isinstance(fix, Refusal) else fix.shifted(offset)


def _conditioning(fix: PanelFix) -> float:
    """Inverse variance proxy of a panel's fix: (image size / distance)^2."""
    distance = float(np.linalg.norm(np.subtract(fix.fix.position_m, fix.beacon.center_m)))
    return fix.blob.area_px / max(distance, 1e-3) ** 2


def choose_and_fuse(fixes: list[PanelFix], rules: RoomRules = RoomRules()) -> PanelFix | None:
    """The best-conditioned fix, with the fixes that agree with it averaged in."""
    if not fixes:
        return None
    ranked = sorted(fixes, key=_conditioning, reverse=True)
    best = ranked[0]
    if not rules.fuse or len(ranked) == 1:
        return best
    agree = [f for f in ranked if np.linalg.norm(f.fix.position_m - best.fix.position_m) <= rules.fuse_gate_m]
    disagree = [f.beacon.id for f in ranked if f not in agree]
    fix = best.fix
    if disagree:
        fix = fix.warned(
            f"fixes from beacons {disagree} disagree with beacon {best.beacon.id} by more than "
            f"{rules.fuse_gate_m * 1000:.0f} mm and were left out"
        )
    if len(agree) > 1:
        covariances = [f.fix.covariance_m2 for f in agree]
        if all(c is not None for c in covariances):
            # weighed by their own uncertainty; the fused covariance is their weighted mean, the
            # bound for errors that the fixes share (one frame: one gravity error, one lens)
            weights = np.array([1.0 / np.trace(np.asarray(c)[:2, :2]) for c in covariances])
            covariance = sum(w * np.asarray(c) for w, c in zip(weights, covariances, strict=True)) / weights.sum()
        else:
            weights, covariance = np.array([_conditioning(f) for f in agree]), None
        position = (weights[:, None] * np.array([f.fix.position_m for f in agree])).sum(axis=0) / weights.sum()
        fused = replace(fix, position_m=position, covariance_m2=covariance)
        fix = fused.warned(f"position fused from beacons {[f.beacon.id for f in agree]}")
    return replace(best, fix=fix)


def vlc_reading(evidence: IdEvidence) -> VlcReading:
    decision = evidence.decide()
    return VlcReading(
        beacon_id=decision.beacon_id,
        confidence=min(1.0, max(0.0, decision.confidence)),
        confident=decision.confident,
        frames=decision.frames,
        chips_seen=decision.chips_seen,
        candidates=evidence.hypotheses,
    )


def foreign_note(vlc: VlcReading | None, beacon_map: BeaconMap, where: str) -> str | None:
    """What the stripes of a panel read when it is none of the map's IDs (`where`: which panel), else None."""
    if vlc is None or vlc.beacon_id is None or beacon_map.beacon(vlc.beacon_id) is not None:
        return None
    return (
        f"the stripes of the panel {where} read as ID {vlc.beacon_id}, not in map '{beacon_map.name}' "
        f"(posterior {vlc.confidence:.2f} that they are of none of its {len(beacon_map.beacons)} beacons, "
        f"{vlc.frames} frame(s)): not used to name it"
    )


def rows_for_chips(chips: float, row_time_s: float, exposure_s: float, rules: StripeRules = StripeRules()) -> int:
    """Rows of a panel whose exposure windows span `chips` chips, with the stripe reader's edge margin
    at each end: a panel cut by the top or bottom border must show this many to be named from one frame."""
    span_s = chips / rules.chip_rate_hz - exposure_s
    return int(math.ceil(max(span_s, 0.0) / row_time_s)) + 2 * rules.edge_margin_px


@dataclass(frozen=True, eq=False)  # identity: holds blobs and fixes
class RoomPanel:
    """One panel of a room frame: its blob, what its stripes read, the map beacon they name (None:
    not named), its fix or the refusal of the one-panel pipeline (None: not tried), and why it
    is not named when that is worth saying (`note`)."""

    blob: BeaconBlob
    vlc: VlcReading | None
    beacon: Beacon | None
    fix: Fix | Refusal | None
    note: str | None = None


@dataclass(frozen=True)
class RoomReading:
    panels: tuple[RoomPanel, ...]
    in_view: int
    problem: str | None  # why this frame cannot carry the code, if it cannot


def _where(blob: BeaconBlob) -> str:
    return f"at ({blob.centroid_px[0]:.0f}, {blob.centroid_px[1]:.0f}) px"


def _cut_panel_note(
    blob: BeaconBlob, chips: float, vlc: VlcReading | None, frame: LumaFrame, rules: RoomRules
) -> str | None:
    """Why the panel cut by the frame border is not named, or None when it is."""
    if chips >= rules.min_cut_chips and vlc is not None and vlc.confident:
        return None
    meta = frame.meta
    assert meta.rolling_shutter_skew_s is not None and meta.exposure_s is not None  # an ID frame's
    row_time = row_time_s(meta.rolling_shutter_skew_s, meta.full_size[1])
    whole = rows_for_chips(MESSAGE_CHIPS - 1, row_time, meta.exposure_s, rules.stripes)
    seen = f"its {blob.bounding_box[3]} visible rows span {chips:.1f} chips of the {MESSAGE_CHIPS}-chip message"
    if chips < rules.min_cut_chips:
        why = f"a cut panel needs at least the {rules.min_cut_chips:g} chips of the ID's bits"
    else:
        best = "nothing" if vlc is None or vlc.beacon_id is None else f"ID {vlc.beacon_id}"
        why = f"they read {best} at posterior {0.0 if vlc is None else vlc.confidence:.2f} only"
    return (
        f"the panel cut by the frame border {_where(blob)} is not named: {seen}, {why}; "
        f"one frame holds the whole ID from {MESSAGE_CHIPS - 1} chips ({whole} rows at this frame's row time)"
    )


def read_room(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: PipelineOptions = PipelineOptions(),
    rules: RoomRules = RoomRules(),
    found: Candidates | None = None,
) -> RoomReading:
    """Every panel of an ID frame of a multi-beacon map: named by its own stripes, and located; `found`: the
    frame's blobs (`frame_blobs` by `rules.candidates.for_beacons(beacon_map.beacons)`) when the caller has them.

    Blobs are judged by the looks of the map's panels (`CandidateRules.for_beacons`). A panel
    cut by the frame border is named like a whole one, from the rows still in view (the stripes
    run along the rows: a panel cut at its left or right keeps all of them), when they span at
    least `rules.min_cut_chips`; if not, or the decoder is not confident, it is not named and the
    panel's `note` says why, with the rows that would do. A named cut panel is located from its
    visible outline by the one-panel pipeline. The named panels are measured on a copy of the
    frame whose stripes are flattened by their codes (`server.vlc.flatten`): the pipeline's
    threshold would cut a striped panel into bars.
    """
    candidates = rules.candidates.for_beacons(beacon_map.beacons)
    found = frame_blobs(frame, candidates, rules.stripes) if found is None else found
    reading = read_id_frame(frame, candidates, rules.stripes, found)
    if reading.problem is not None:
        return RoomReading((), len(found.blobs), reading.problem)
    ids = tuple(sorted(b.id for b in beacon_map.beacons))  # the hypotheses, with "none of them"
    named: list[tuple[BeaconBlob, VlcReading | None, Beacon | None, str | None]] = []
    for panel in reading.panels:
        blob = panel.blob
        vlc: VlcReading | None = None
        note: str | None = None
        if panel.observation is not None:
            evidence = IdEvidence(map_ids=ids, rules=rules.stripes)
            evidence.add(panel.observation)
            vlc = vlc_reading(evidence)
        if blob.cut_off:
            chips = 0.0 if panel.observation is None else panel.observation.chips_seen
            note = _cut_panel_note(blob, chips, vlc, frame, rules)
        beacon = None
        if note is None and vlc is not None and vlc.confident and vlc.beacon_id is not None:
            beacon = beacon_map.beacon(vlc.beacon_id)  # a confident ID is a map ID
        note = "; ".join(n for n in (note, foreign_note(vlc, beacon_map, _where(blob))) if n) or None
        named.append((blob, vlc, beacon, note))
    plain, flat_notes = flattened(frame, found, [(blob, beacon) for blob, _, beacon, _ in named], candidates, rules)
    blobs = [blob for blob, *_ in named]
    panels: list[RoomPanel] = []
    for blob, vlc, beacon, note in named:
        fix: Fix | Refusal | None = None
        if beacon is not None:
            others = [b for b in blobs if b is not blob]
            fix = locate_panel(plain, blob, others, beacon, BeaconIdSource.vlc, options, found.levels, rules)
            if isinstance(fix, Fix) and blob in flat_notes:
                fix = fix.warned(flat_notes[blob])
            elif isinstance(fix, Refusal) and blob in flat_notes:
                fix = replace(fix, warnings=fix.warnings + (flat_notes[blob],))
        panels.append(RoomPanel(blob, vlc, beacon, fix, note))
    return RoomReading(tuple(panels), len(found.blobs), None)


def flattened(
    frame: LumaFrame,
    found: Candidates,
    named: list[tuple[BeaconBlob, Beacon | None]],
    candidates: CandidateRules,
    rules: RoomRules,
) -> tuple[LumaFrame, dict[BeaconBlob, str]]:
    """A copy of ID frame `frame` with the stripes of every named panel flattened by its own code
    (`server.vlc.flatten`), and, per panel that could not be, why."""
    meta = frame.meta
    assert meta.rolling_shutter_skew_s is not None and meta.exposure_s is not None  # an ID frame's
    row_time = row_time_s(meta.rolling_shutter_skew_s, meta.full_size[1])
    pixels = np.array(frame.pixels)
    notes: dict[BeaconBlob, str] = {}
    for blob, beacon in named:
        if beacon is None:
            continue
        y0, x0, mask = blob_mask(frame.pixels, blob, found, candidates, margin_px=rules.flatten.grow_px + 4)
        problem = flatten_stripes(
            pixels,
            mask,
            (y0, x0),
            found.levels.background,
            beacon.id,
            row_time,
            meta.exposure_s,
            rules.flatten,
            rules.stripes.chip_rate_hz,
        )
        if problem is not None:
            notes[blob] = f"the stripes of beacon {beacon.id} were not flattened before measuring it: {problem}"
    pixels.flags.writeable = False
    return LumaFrame(pixels=pixels, meta=meta, camera=frame.camera), notes


def locate_in_room(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: PipelineOptions = PipelineOptions(),
    rules: RoomRules = RoomRules(),
) -> LocateResult:
    """A fix from a frame of a multi-beacon map whose IDs come from the frame's own stripes (`read_room`)."""
    return room_result(read_room(frame, beacon_map, options, rules), beacon_map, rules)


def room_result(room: RoomReading, beacon_map: BeaconMap, rules: RoomRules = RoomRules()) -> LocateResult:
    """The contract's result of a room frame's panels: the best fix with the agreeing ones fused, or why
    there is none; every panel's note (a cut panel not named) among the warnings either way."""
    if room.problem is not None:
        return refused(
            Refusal(
                FailureReason.unknown_beacon,
                f"map '{beacon_map.name}' has {len(beacon_map.beacons)} beacons and no beacon ID was read: "
                f"this frame cannot carry the code ({room.problem}); send ID frames (docs/vlc.md)",
            ),
            beacons_in_view=room.in_view,
        )
    notes = tuple(p.note for p in room.panels if p.note is not None)
    fixes = [
        PanelFix(p.blob, p.beacon, p.fix, p.vlc) for p in room.panels if isinstance(p.fix, Fix) and p.beacon is not None
    ]
    refusals = [p.fix for p in room.panels if isinstance(p.fix, Refusal)]
    best = choose_and_fuse(fixes, rules)
    if best is None:
        refusal = (
            refusals[0]
            if refusals
            else Refusal(
                FailureReason.unknown_beacon,
                f"no panel with a confidently read ID among {room.in_view} in view",
            )
        )
        refusal = replace(refusal, warnings=refusal.warnings + notes)
        readings = [p.vlc for p in room.panels if p.vlc is not None]
        top = max(readings, key=lambda r: r.confidence, default=None)
        return refused(refusal, vlc=top, beacons_in_view=room.in_view)
    return located(best.fix.warned(*notes), vlc=best.vlc, beacons_in_view=room.in_view)
