"""Stripes of every panel in one ID frame: blobs (server.vision.beacons) -> row signals (decoder)."""

from __future__ import annotations

from dataclasses import dataclass

from server.ingest import LumaFrame
from server.vision.beacons import BeaconBlob, CandidateRules, Candidates, blob_mask
from server.vlc.capture import frame_blobs, id_frame_problem
from server.vlc.decoder import StripeObservation, StripeRules, panel_pixels, read_panel_stripes, row_time_s
from server.vlc.stripes import TurnedRules, turned_frame_problem


@dataclass(frozen=True)
class PanelStripes:
    blob: BeaconBlob
    centroid_norm: tuple[float, float]  # fraction of the full frame: comparable across frame sizes and crops
    observation: StripeObservation | None  # None: too few rows inside the panel


@dataclass(frozen=True)
class IdFrameReading:
    panels: tuple[PanelStripes, ...]
    problem: str | None  # why this frame cannot carry stripes, if it cannot


def read_id_frame(
    frame: LumaFrame,
    candidates: CandidateRules = CandidateRules(),
    rules: StripeRules = StripeRules(),
    found: Candidates | None = None,
) -> IdFrameReading:
    """The stripe signal of each beacon-shaped blob of `frame` (cut-off ones included); `found`: the
    frame's blobs when the caller has them already (`frame_blobs`: their dark rows bridged)."""
    problem = id_frame_problem(frame, rules)
    if problem is not None:
        return IdFrameReading((), problem)
    meta = frame.meta
    skew_s, timestamp_ns, exposure_s = meta.rolling_shutter_skew_s, meta.timestamp_ns, meta.exposure_s
    assert skew_s is not None and timestamp_ns is not None and exposure_s is not None  # id_frame_problem checked
    row_time = row_time_s(skew_s, meta.full_size[1])  # the sensor's rows, crop or not
    first_row_s = timestamp_ns * 1e-9 + meta.full_offset[1] * row_time
    found = frame_blobs(frame, candidates, rules) if found is None else found  # dark rows between stripes bridged
    masks = [blob_mask(frame.pixels, blob, found, candidates) for blob in found.blobs]
    # each mask shrunk once, for both the turned-frame test and the row reader
    shrunk = [panel_pixels(frame.pixels, mask, (y0, x0), rules.edge_margin_px) for y0, x0, mask in masks]
    # stripes along the columns read as nonsense along the rows: say so instead, before reading them
    boxes = [blob.bounding_box for blob in found.blobs]
    turned = turned_frame_problem(frame.pixels, shrunk, boxes, TurnedRules(edge_margin_px=rules.edge_margin_px))
    if turned is not None:
        return IdFrameReading((), turned)
    panels = []
    for blob, panel in zip(found.blobs, shrunk, strict=True):
        observation = read_panel_stripes(panel, first_row_s, row_time, exposure_s, rules)
        centroid = meta.fraction_of_full_frame(*blob.centroid_px)
        panels.append(PanelStripes(blob, centroid, observation))
    return IdFrameReading(tuple(panels), None)
