"""A beacon survey: chains the stages, no geometry of its own.

frames -> named panels and their points (`sightings`) -> the graph from the anchor and a start
(`chain`) -> the bundle adjustment (`adjust`), once more without the sightings it finds far off ->
the map's compass bearing (`bearing`) -> the contract's `SurveyReport`.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import numpy as np

from server.camera import ProfileTable
from server.ingest import LumaFrame
from server.survey.adjust import Adjusted, adjust
from server.survey.bearing import map_bearing
from server.survey.chain import chain_start
from server.survey.rules import SurveyInputError, SurveyRefused, SurveyRules
from server.survey.sightings import FrameSightings, check_labels, frame_sightings
from shared_schemas import BeaconMap
from shared_schemas.survey import PanelLabel, SkippedFrame, SurveyedBeacon, SurveyReport


@dataclass(frozen=True)
class SurveyFrame:
    name: str  # how the report names it: a file name or a sample ID
    frame: LumaFrame
    labels: list[PanelLabel] = field(default_factory=list)


def check_request(sketch: BeaconMap, anchor: int, frames: list[tuple[str, list[PanelLabel]]]) -> None:
    """What can be refused before any frame is read: the anchor, the sketch's panels, the labels."""
    if sketch.beacon(anchor) is None:
        raise SurveyInputError(
            f"anchor {anchor} is not in sketch '{sketch.name}' (its beacons: {sorted(b.id for b in sketch.beacons)})",
            field="anchor",
        )
    for k, beacon in enumerate(sketch.beacons):
        if not beacon.has_corners:
            raise SurveyInputError(
                f"beacon {beacon.id} of the sketch is a circle: its yaw cannot be seen and a survey fits panels "
                f"with corners only",
                field=f"sketch.beacons.{k}.shape",
            )
    for k, (name, labels) in enumerate(frames):
        check_labels(labels, sketch, name, f"samples.{k}.labels")


def _without_outliers(
    frames: list[FrameSightings], adjusted: Adjusted, rules: SurveyRules
) -> tuple[list[FrameSightings], list[SkippedFrame]]:
    """The frames without the sightings whose points the fit leaves far off (against their own sigma);
    frames left with fewer than two panels are skipped."""
    whitened = [rms for frame in adjusted.sighting_chi for rms in frame]
    limit = rules.outlier_factor * float(np.median(whitened))
    kept: list[FrameSightings] = []
    skipped: list[SkippedFrame] = []
    for frame, rms_each, chi_each in zip(frames, adjusted.sighting_rms_px, adjusted.sighting_chi, strict=True):
        judged = list(zip(frame.sightings, rms_each, chi_each, strict=True))
        good = tuple(s for s, _, chi in judged if chi <= limit)
        off = [f"beacon {s.beacon.id} {rms:.2f} px" for s, rms, chi in judged if chi > limit]
        if len(good) >= 2:
            note = (f"left out after the first fit: {', '.join(off)} off",) if off else ()
            kept.append(replace(frame, sightings=good, notes=frame.notes + note))
        else:
            skipped.append(
                SkippedFrame(
                    name=frame.name,
                    why=f"the fit leaves its panels far off ({', '.join(off)} RMS; the limit is "
                    f"{rules.outlier_factor:g} times the median): a wrong label, or a panel that moved or smeared",
                )
            )
    return kept, skipped


def survey(
    frames: Iterable[SurveyFrame],
    sketch: BeaconMap,
    anchor: int,
    name: str,
    rules: SurveyRules = SurveyRules(),
    profiles: ProfileTable | None = None,
) -> SurveyReport:
    """The surveyed map of `sketch`'s panels from `frames` (read once, in order: a generator that decodes each
    frame when asked keeps one image in memory); raises `SurveyInputError` or `SurveyRefused`.
    `profiles`: the device profiles the frames were decoded with (default: the bundled ones)."""
    check_request(sketch, anchor, [])
    used: list[FrameSightings] = []
    skipped: list[SkippedFrame] = []
    # one frame at a time: only its sightings are kept, so a caller that reads frames lazily holds one image
    for k, frame in enumerate(frames):
        check_labels(frame.labels, sketch, frame.name, f"samples.{k}.labels")
        seen = frame_sightings(frame.frame, frame.name, frame.labels, sketch, rules, profiles)
        (skipped if isinstance(seen, SkippedFrame) else used).append(seen)  # type: ignore[arg-type]
    if not used:
        first = "; ".join(f"'{s.name}': {s.why}" for s in skipped[:3])
        raise SurveyRefused(f"no frame sees two named panels, so nothing ties the panels together ({first})")
    adjusted = adjust(used, chain_start(used, sketch, anchor), anchor, rules)
    kept, dropped = _without_outliers(used, adjusted, rules)
    if dropped or sum(len(f.sightings) for f in kept) < sum(len(f.sightings) for f in used):
        if not kept:
            raise SurveyRefused("the fit leaves every frame's panels far off: " + dropped[0].why)
        used, skipped = kept, skipped + dropped
        adjusted = adjust(used, chain_start(used, sketch, anchor), anchor, rules)
    bearing = map_bearing(
        [c.rotation_wc for c in adjusted.cameras], [f.compass_bearing_deg for f in used], rules.compass_bias_sigma_deg
    )
    beacons = []
    for beacon in sketch.beacons:
        estimate = adjusted.panels[beacon.id]
        beacons.append(
            beacon.model_copy(
                update={
                    "center_m": [float(v) for v in estimate.pose.center_m],
                    "yaw_deg": estimate.pose.yaw_deg,
                }
            )
        )
    surveyed = sketch.model_copy(
        update={
            "name": name,
            "beacons": beacons,
            # the anchor keeps the sketch's frame, so the sketch's bearing still holds when no frame measured one
            "bearing_deg": sketch.bearing_deg if bearing is None else bearing.bearing_deg,
        }
    )
    return SurveyReport(
        map=BeaconMap.model_validate(surveyed.model_dump(by_alias=True)),
        beacons=[
            SurveyedBeacon(
                beacon_id=b.id,
                center_m=[float(v) for v in adjusted.panels[b.id].pose.center_m],
                yaw_deg=adjusted.panels[b.id].pose.yaw_deg,
                center_sigma_m=[float(v) for v in adjusted.panels[b.id].center_sigma_m],
                yaw_sigma_deg=adjusted.panels[b.id].yaw_sigma_deg,
                frames=adjusted.panels[b.id].frames,
            )
            for b in sketch.beacons
        ],
        frames_used=len(used),
        skipped=skipped,
        rms_px=adjusted.rms_px,
        bearing_deg=None if bearing is None else bearing.bearing_deg,
        bearing_sigma_deg=None if bearing is None else bearing.sigma_deg,
    )
