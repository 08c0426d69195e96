"""The one entry point for locating a frame: chooses the path, once, for every caller.

- the beacon in view is known (a one-beacon map, or `beacon_id` given): the one-panel
  pipeline (`server.pipeline`);
- a map of several beacons, no device: the frame's own stripes name its panels
  (`server.rooms.locate_in_room`);
- a map of several beacons, from a device: the device's session combines its ID frames and
  its track (`server.tracking.devices`).

The API, the command line and the benchmarks call `locate`; nothing below imports this module.
"""

from __future__ import annotations

from server.ingest import LumaFrame
from server.options import LocateOptions
from server.outcomes import Refusal, located, refused
from server.pipeline import locate_beacon
from server.rooms import locate_in_room
from server.tracking.devices import Devices
from shared_schemas import BeaconIdSource, BeaconMap, FailureReason, LocateResult


def locate(
    frame: LumaFrame,
    beacon_map: BeaconMap,
    options: LocateOptions = LocateOptions(),
    *,
    beacon_id: int | None = None,
    device_id: str | None = None,
    devices: Devices | None = None,
) -> LocateResult:
    """Position and pose of the camera that took `frame`, or the reason there is none.

    `beacon_id`: the map beacon in view, when known from elsewhere; `device_id` and `devices`:
    the sender and the sessions of this process, for maps of several beacons.
    """
    if beacon_id is not None:
        beacon = beacon_map.beacon(beacon_id)
        if beacon is None:
            return refused(
                Refusal(FailureReason.unknown_beacon, f"beacon {beacon_id} is not in map '{beacon_map.name}'")
            )
        return _one_panel(frame, beacon, BeaconIdSource.vlc, options)
    if len(beacon_map.beacons) == 1:
        return _one_panel(frame, beacon_map.beacons[0], BeaconIdSource.single_beacon_map, options)
    if device_id is not None and devices is not None:
        return devices.locate(device_id, frame, beacon_map, options)
    return locate_in_room(frame, beacon_map, options.pipeline, options.room)


def _one_panel(frame: LumaFrame, beacon, id_source: BeaconIdSource, options: LocateOptions) -> LocateResult:
    fix = locate_beacon(frame, beacon, options.pipeline, id_source)
    return refused(fix) if isinstance(fix, Refusal) else located(fix)
