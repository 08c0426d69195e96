"""The one entry point for locating a frame: chooses the path, once, for every caller.

- the beacon in view is known (a one-beacon map, or `beacon_id` given): the one-panel
  pipeline (`server.pipeline`);
- a map of several beacons, no device: the frame's own stripes name its panels
  (`server.rooms.locate_in_room`);
- a map of several beacons, from a device: the device's session combines its ID frames and
  its track (`server.tracking.devices`).

The API, the command line and the benchmarks call `locate`; nothing below imports this module.
A known tone curve (`tone_curve: srgb`) is undone here, once, before any path reads the pixels
(`server.tone.linearized`).

A numerical failure anywhere below (OpenCV, numpy, float overflow: numbers within the contract's
ranges that still break the arithmetic) is a refusal with reason `numerical_failure`, logged with
its traceback on `lumipose.pipeline`, never an exception; a `FrameError` (bad input) still raises.
"""

from __future__ import annotations

import logging
import re
import threading
import traceback
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from server.geometry import wrap_deg
from server.ingest import LumaFrame
from server.options import LocateOptions
from server.outcomes import Refusal, located, refused, with_camera
from server.pipeline import locate_beacon
from server.plausibility import odd_fix_warning
from server.rooms import locate_in_room
from server.tone import linearized
from server.tracking.devices import DeviceSessions
from shared_schemas import BeaconIdSource, BeaconMap, FailureReason, LocateResult
from shared_schemas.models import MAX_WARNINGS

LOG = logging.getLogger("lumipose.pipeline")
# What the stages' arithmetic raises on numbers it cannot handle: OpenCV's checks, a singular or
# non-converging matrix, float overflow or division by zero. Not ValueError: that is what most
# plain bugs raise (unpacking, broadcasting, a result model built wrong), and a bug must stay a
# counted 500 (server.api.errors.BugCatcher), not pass for the frame's fault.
NUMERICAL_ERRORS: tuple[type[Exception], ...] = (cv2.error, np.linalg.LinAlgError, ArithmeticError)
_SERVER_DIR = Path(__file__).resolve().parent


def locate(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: LocateOptions = LocateOptions(),
    *,
    beacon_id: int | None = None,
    device_id: str | None = None,
    devices: DeviceSessions | None = None,
) -> LocateResult:
    """Position and pose of the camera that took `frame`, or the reason there is none.

    `beacon_id`: the map beacon in view, when known from elsewhere; `device_id` and `devices`:
    the sender and the device sessions (this process's, or shared in Redis), for maps of several beacons.
    """
    try:
        result = _dispatch(frame, beacon_map, options, beacon_id, device_id, devices)
        odd = odd_fix_warning(result, beacon_map)
        if odd is not None:
            result = result.model_copy(update={"warnings": [*result.warnings, odd][-MAX_WARNINGS:]})
        # every result says which intrinsics it rests on (a photo's may be a rough EXIF guess): a refused
        # photo's user needs it most, to see whether the camera was the trouble
        return with_camera(result, frame.camera_used)
    except NUMERICAL_ERRORS as error:
        where = _where(error)
        LOG.warning("numerical failure in %s on map '%s': %r", where, beacon_map.name, error, exc_info=True)
        first_line = (_opencv_message(str(error)).strip().splitlines() or [""])[0][:200]
        failure = Refusal(
            FailureReason.numerical_failure,
            f"the frame's numbers (camera, distortion, gravity, times) or the map's broke the arithmetic "
            f"in {where}: {'cv2.error' if isinstance(error, cv2.error) else type(error).__name__}: {first_line}",
        )
        return with_camera(refused(failure), frame.camera_used)


def _opencv_message(text: str) -> str:
    """A cv2.error's own words, without OpenCV's version and source path ("OpenCV(4.x) /path:272: error: ...").
    (cv2.error's `err` attribute is set on the class, so another thread's error may have replaced it.)"""
    match = re.search(r": error: (.*)", text)
    return match[1] if match else text


def _where(error: BaseException) -> str:
    """`module.function` of the innermost server frame the error passed through."""
    where = "the pipeline"
    for entry in traceback.extract_tb(error.__traceback__):
        path = Path(entry.filename).resolve()
        if path.is_relative_to(_SERVER_DIR):
            module = ".".join(("server", *path.relative_to(_SERVER_DIR).with_suffix("").parts))
            where = f"{module}.{entry.name}"
    return where


def in_device_session(beacon_map: BeaconMap, beacon_id: int | None, device_id: str | None) -> bool:
    """Whether `locate` takes a frame in its device's session: a device, a map of several beacons, none named."""
    return device_id is not None and beacon_id is None and len(beacon_map.beacons) > 1


def _dispatch(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: LocateOptions,
    beacon_id: int | None,
    device_id: str | None,
    devices: DeviceSessions | None,
) -> LocateResult:
    options = _FOR_MAP.options(options, beacon_map)
    # Every path below (one panel, rooms, device sessions with their ID frames) reads light: the
    # stripe decoder's model (a row's mean = gain x the code's box average + offset) and the
    # flattening (a row divided by its gain) are linear in light, as the clipped-edge model is.
    frame = linearized(frame)
    frame = _with_map_heading(frame, beacon_map)
    if beacon_id is not None:
        beacon = beacon_map.beacon(beacon_id)
        if beacon is None:
            return refused(
                Refusal(FailureReason.unknown_beacon, f"beacon {beacon_id} is not in map '{beacon_map.name}'")
            )
        return _one_panel(frame, beacon, BeaconIdSource.vlc, options)
    if len(beacon_map.beacons) == 1:
        return _one_panel(frame, beacon_map.beacons[0], BeaconIdSource.single_beacon_map, options)
    if devices is not None and in_device_session(beacon_map, beacon_id, device_id):
        assert device_id is not None
        return devices.locate(device_id, frame, beacon_map, options)
    return locate_in_room(frame, beacon_map, options.pipeline, options.room)


class _OptionsForMap:
    """`options.for_map(beacon_map)` made once for the same two objects, not for every frame (~0.1 ms of
    dataclass copies): the service's options for a request's choices (`Services.options_for`) and a stored map
    (`server.store` parses a file anew only when it changed) are the same objects from one frame to the next.
    Keyed by identity and holding both, so that no id is reused while kept; `keep` pairs, the oldest dropped.
    Safe from any thread."""

    def __init__(self, keep: int) -> None:
        self.keep = keep
        self._made: dict[tuple[int, int], tuple[LocateOptions, BeaconMap, LocateOptions]] = {}
        self._lock = threading.Lock()

    def options(self, options: LocateOptions, beacon_map: BeaconMap) -> LocateOptions:
        if options.pipeline.diagnostics is not None:  # one request's (a picture asked for): never seen again
            return options.for_map(beacon_map)
        key = (id(options), id(beacon_map))
        with self._lock:
            kept = self._made.get(key)
        if kept is not None and kept[0] is options and kept[1] is beacon_map:
            return kept[2]
        made = options.for_map(beacon_map)
        with self._lock:
            self._made[key] = (options, beacon_map, made)
            while len(self._made) > self.keep:
                del self._made[next(iter(self._made))]
        return made


_FOR_MAP = _OptionsForMap(keep=16)


def _with_map_heading(frame: LumaFrame, beacon_map: BeaconMap) -> LumaFrame:
    """A frame with a compass reading but no heading gets one from the map's surveyed bearing.

    heading_deg = bearing_deg - compass_bearing_deg (docs/contract.md): a phone that has not read
    the map's bearing, or a client that only knows its compass, still resolves a square's four
    look-alike orientations. A heading the frame gives is its sender's word and is kept.
    """
    meta = frame.meta
    if meta.heading_deg is not None or meta.compass_bearing_deg is None or beacon_map.bearing_deg is None:
        return frame
    heading = wrap_deg(beacon_map.bearing_deg - meta.compass_bearing_deg)
    return replace(frame, meta=meta.model_copy(update={"heading_deg": heading}))


def _one_panel(frame: LumaFrame, beacon, id_source: BeaconIdSource, options: LocateOptions) -> LocateResult:
    fix = locate_beacon(frame, beacon, options.pipeline, id_source)
    return refused(fix) if isinstance(fix, Refusal) else located(fix)
