"""Whether a fix is physically odd for its map: a warning a user needs, not a refusal.

One rule, for a map whose panels all hang above its z = 0 (the floor, or the phone's height: the map frame of
docs/quickstart.md): a camera farther below z = 0 than its panel hangs above it sees the panel from more than
twice as far as z = 0 is, which no one holding a phone under a ceiling does, while a phone held lower than z = 0
(the floor's 0.3 m under a bench's grid, the knee under a z = 0 taken at the hand) stays within it. The usual cause
is the panel's size: a fix's distance scales with it (a 0.6 m panel in the map for a 0.174 m one in the photo puts
the camera 3.45 times as far), as it does with the focal length.
"""

from __future__ import annotations

import math

from shared_schemas import Beacon, BeaconMap, LocateResult


def odd_fix_warning(result: LocateResult, beacon_map: BeaconMap) -> str | None:
    """The warning for a fix farther below z = 0 than its panel hangs above it, in a map whose panels are all
    above z = 0; else None."""
    if not result.ok or result.position_m is None or result.beacon_id is None:
        return None
    beacon = beacon_map.beacon(result.beacon_id)
    if beacon is None or min(b.center_m[2] for b in beacon_map.beacons) <= 0:
        return None
    depth_m = -result.position_m[2]
    if depth_m <= beacon.center_m[2]:
        return None
    distance_m = math.dist(result.position_m, beacon.center_m)
    return (
        f"the camera is {depth_m:.2f} m below the map's z = 0, {distance_m:.2f} m from panel {beacon.id} that the map "
        f"hangs {beacon.center_m[2]:.2f} m above it: a fix's distance scales with the panel's size, so check "
        f"{_size(beacon)} against the panel (docs/quickstart.md, measuring a panel)"
    )


def _size(beacon: Beacon) -> str:
    if beacon.diameter_m is not None:
        return f"diameter_m ({beacon.diameter_m:g} m)"
    if beacon.side_m is not None:
        return f"side_m ({beacon.side_m:g} m)"
    return f"width_m, height_m ({beacon.width_m:g} x {beacon.height_m:g} m)"
