"""Rooms with many beacons: one fix per panel in view, the best chosen, agreeing ones fused.

`server.pipeline.locate` handles one panel. Here every beacon-shaped blob of the frame
(`server.vision.beacons`) that has an ID gets its own crop (the other panels blanked to the
background level, the principal point shifted, so OpenCV's distortion model stays exact) and
its own `locate`. The fix of the largest complete panel is the best conditioned (the error
of a square's pose grows with distance over its image size); the other fixes are averaged
in, weighted by that same measure, only when they agree with it within `fuse_gate_m` (a
panel with a wrong ID would move the fix by a beacon spacing, so it is left out, and said).

`locate_in_room` serves a multi-beacon map without a given ID and without a device session
(`server.locator` chooses): it reads the frame's own stripes (a short-exposure frame,
docs/vlc.md); a device's session (`server.tracking`) instead brings IDs read from the ID
frames beside a pose frame, and uses `locate_panel` and `choose_and_fuse` from here.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from server.ingest import LumaFrame
from server.outcomes import Fix, Refusal, located, refused
from server.pipeline import PipelineOptions, locate_beacon
from server.vision.beacons import BeaconBlob, CandidateRules, find_beacon_blobs
from server.vlc.decoder import IdEvidence, StripeRules
from server.vlc.reader import read_id_frame
from shared_schemas import Beacon, BeaconIdSource, BeaconMap, FailureReason, LocateResult, VlcReading


@dataclass(frozen=True)
class RoomRules:
    crop_margin_px: int = 48
    fuse_gate_m: float = 0.03
    fuse: bool = True
    candidates: CandidateRules = CandidateRules()
    stripes: StripeRules = StripeRules()


@dataclass(frozen=True, eq=False)  # identity: fixes hold numpy arrays
class PanelFix:
    """A fix from one panel of the frame, with the blob it came from and the ID reading that named it."""

    blob: BeaconBlob
    beacon: Beacon
    fix: Fix
    vlc: VlcReading | None = None


def crop_frame(
    frame: LumaFrame, blob: BeaconBlob, others: list[BeaconBlob], margin_px: int, background_dn: float
) -> tuple[LumaFrame, tuple[int, int]]:
    """`frame` cut to `blob`'s box plus a margin (at least the box's size), other blobs blanked; and (x0, y0)."""
    height, width = frame.pixels.shape
    x, y, w, h = blob.bounding_box
    # the pipeline takes the crop's median as its background: the panel must stay a small part of it
    margin_px = max(margin_px, w, h)
    x0, y0 = max(0, x - margin_px), max(0, y - margin_px)
    x1, y1 = min(width, x + w + margin_px), min(height, y + h + margin_px)
    pixels = np.array(frame.pixels[y0:y1, x0:x1])
    for other in others:
        ox, oy, ow, oh = other.bounding_box
        pad = 16
        ax0, ay0 = max(ox - pad - x0, 0), max(oy - pad - y0, 0)
        ax1, ay1 = min(ox + ow + pad - x0, x1 - x0), min(oy + oh + pad - y0, y1 - y0)
        if ax1 > ax0 and ay1 > ay0:
            pixels[ay0:ay1, ax0:ax1] = np.uint8(round(background_dn))
    pixels.flags.writeable = False
    camera = frame.camera.model_copy(update={"cx": frame.camera.cx - x0, "cy": frame.camera.cy - y0})
    meta = frame.meta.model_copy(update={"width": x1 - x0, "height": y1 - y0, "row_stride": None, "camera": camera})
    return LumaFrame(pixels=pixels, meta=meta, camera=camera), (x0, y0)


def locate_panel(
    frame: LumaFrame,
    blob: BeaconBlob,
    others: list[BeaconBlob],
    beacon: Beacon,
    id_source: BeaconIdSource,
    options: PipelineOptions,
    background_dn: float,
    rules: RoomRules = RoomRules(),
) -> Fix | Refusal:
    """The one-panel pipeline on `blob` alone as map beacon `beacon`; pixels in the full frame."""
    crop, offset = crop_frame(frame, blob, others, rules.crop_margin_px, background_dn)
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
        weights = np.array([_conditioning(f) for f in agree])
        position = (weights[:, None] * np.array([f.fix.position_m for f in agree])).sum(axis=0) / weights.sum()
        fix = replace(fix, position_m=position).warned(f"position fused from beacons {[f.beacon.id for f in agree]}")
    return replace(best, fix=fix)


def vlc_reading(evidence: IdEvidence) -> VlcReading:
    decision = evidence.decide()
    return VlcReading(
        beacon_id=decision.beacon_id,
        confidence=min(1.0, max(0.0, decision.confidence)),
        confident=decision.confident,
        frames=decision.frames,
        chips_seen=decision.chips_seen,
        candidates=len(evidence.candidates),
    )


def locate_in_room(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: PipelineOptions = PipelineOptions(),
    rules: RoomRules = RoomRules(),
) -> LocateResult:
    """A fix from a frame of a multi-beacon map whose IDs come from the frame's own stripes."""
    found = find_beacon_blobs(frame.pixels, rules.candidates)
    reading = read_id_frame(frame, rules.candidates, rules.stripes, found)
    if reading.problem is not None:
        return refused(
            Refusal(
                FailureReason.unknown_beacon,
                f"map '{beacon_map.name}' has {len(beacon_map.beacons)} beacons and no beacon ID was read: "
                f"this frame cannot carry the code ({reading.problem}); send ID frames (docs/vlc.md)",
            ),
            beacons_in_view=len(found.blobs),
        )
    ids = tuple(sorted(b.id for b in beacon_map.beacons))  # preferred, never the only candidates
    blobs = [p.blob for p in reading.panels]
    fixes: list[PanelFix] = []
    refusals: list[Refusal] = []
    readings: list[VlcReading] = []
    for panel in reading.panels:
        if panel.observation is None:
            continue
        evidence = IdEvidence(preferred=ids, rules=rules.stripes)
        evidence.add(panel.observation)
        vlc = vlc_reading(evidence)
        readings.append(vlc)
        beacon = beacon_map.beacon(vlc.beacon_id) if vlc.confident and vlc.beacon_id is not None else None
        if beacon is None or panel.blob.cut_off:
            continue
        fix = locate_panel(
            frame,
            panel.blob,
            [b for b in blobs if b is not panel.blob],
            beacon,
            BeaconIdSource.vlc,
            options,
            found.levels.background,
            rules,
        )
        if isinstance(fix, Refusal):
            refusals.append(fix)
        else:
            fixes.append(PanelFix(panel.blob, beacon, fix, vlc))
    best = choose_and_fuse(fixes, rules)
    if best is None:
        refusal = (
            refusals[0]
            if refusals
            else Refusal(
                FailureReason.unknown_beacon, f"no complete panel with a confidently read ID among {len(blobs)} in view"
            )
        )
        top = max(readings, key=lambda r: r.confidence, default=None)
        return refused(refusal, vlc=top, beacons_in_view=len(blobs))
    return located(best.fix, vlc=best.vlc, beacons_in_view=len(blobs))
