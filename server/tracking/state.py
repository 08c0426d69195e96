"""A device's state as plain data: what a store outside the process (Redis) keeps between its requests.

A device's record (`server.tracking.devices`) is its session and the stripes of the ID frames
waiting for its next pose frame. `dump_device` writes it as JSON (numbers exact: floats as
Python writes them, arrays as base64 of their float64 bytes); `load_device` reads it back
against the map and rules of the request that loads it. What the process derives from the map
and the settings (the rules, the decoder's candidate IDs, caches) is not stored: a record
written by one replica is read by another with its own, equal, settings. A record of another
map (the map changed, or the device moved to another room) keeps its waiting stripes and
starts a new session, as in memory. JSON rather than pickle: a value in a shared store must
not be able to run code in the process that reads it.
"""

from __future__ import annotations

import base64
import hashlib
import json
from collections import deque
from collections.abc import Sequence
from typing import Any

import numpy as np

from server.tracking.filter import FilterState
from server.tracking.naming import NamingStats, PanelTrack
from server.tracking.session import DeviceSession, IdSighting, SessionRules, WaitingIdFrame
from server.tracking.track import Track
from server.vlc.decoder import StripeObservation
from shared_schemas import BeaconMap, VlcReading

STATE_FORMAT = 1  # bumped when the layout changes: a record of another format is dropped, not misread


class StateError(ValueError):
    """A stored record that cannot be read (another format, or damaged): the device starts afresh."""


def map_digest(beacon_map: BeaconMap) -> str:
    """The map a session was made for: a record of another map starts a new session."""
    text = beacon_map.model_dump_json(by_alias=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def dump_device(session: DeviceSession | None, waiting: Sequence[WaitingIdFrame]) -> bytes:
    record = {
        "format": STATE_FORMAT,
        "session": None if session is None else _session(session),
        "waiting": [_waiting(w) for w in waiting],
    }
    return json.dumps(record, separators=(",", ":")).encode()


def load_device(
    data: bytes, beacon_map: BeaconMap, rules: SessionRules
) -> tuple[DeviceSession | None, deque[WaitingIdFrame]]:
    """The session (None when it was made for another map) and the waiting ID frames of a record."""
    try:
        record = json.loads(data)
        if not isinstance(record, dict) or record.get("format") != STATE_FORMAT:
            raise StateError(f"a device record of format {record.get('format') if isinstance(record, dict) else '?'}")
        waiting = deque(_read_waiting(w) for w in record["waiting"])
        stored = record["session"]
        if stored is None or stored["map"] != map_digest(beacon_map):
            return None, waiting
        return _read_session(stored, beacon_map, rules), waiting
    except StateError:
        raise
    except (ValueError, KeyError, TypeError, IndexError, RecursionError) as error:
        # RecursionError: JSON nested thousands deep (json.loads recurses per level); not a record we wrote
        raise StateError(f"a damaged device record: {type(error).__name__}: {str(error)[:200]}") from None


def _array(values: np.ndarray) -> dict[str, Any]:
    array = np.ascontiguousarray(values, dtype=np.float64)
    return {"shape": list(array.shape), "f8": base64.b64encode(array.tobytes()).decode("ascii")}


def _read_array(stored: dict[str, Any]) -> np.ndarray:
    array = np.frombuffer(base64.b64decode(stored["f8"], validate=True), dtype=np.float64)
    return array.reshape(stored["shape"]).copy()  # writable, as the live objects' arrays are


def _observation(o: StripeObservation) -> dict[str, Any]:
    return {
        "timestamp_s": o.timestamp_s,
        "exposure_s": o.exposure_s,
        "row_offsets_s": _array(o.row_offsets_s),
        "values_dn": _array(o.values_dn),
        "sigma_dn": _array(o.sigma_dn),
        "position": _array(o.position),
        "chips_seen": o.chips_seen,
    }


def _read_observation(stored: dict[str, Any]) -> StripeObservation:
    return StripeObservation(
        timestamp_s=float(stored["timestamp_s"]),
        exposure_s=float(stored["exposure_s"]),
        row_offsets_s=_read_array(stored["row_offsets_s"]),
        values_dn=_read_array(stored["values_dn"]),
        sigma_dn=_read_array(stored["sigma_dn"]),
        position=_read_array(stored["position"]),
        chips_seen=float(stored["chips_seen"]),
    )


def _waiting(frame: WaitingIdFrame) -> dict[str, Any]:
    return {
        "t_s": frame.t_s,
        "sightings": [{"at": list(s.centroid_norm), "stripes": _observation(s.observation)} for s in frame.sightings],
    }


def _read_waiting(stored: dict[str, Any]) -> WaitingIdFrame:
    sightings = tuple(
        IdSighting((float(s["at"][0]), float(s["at"][1])), _read_observation(s["stripes"])) for s in stored["sightings"]
    )
    return WaitingIdFrame(None if stored["t_s"] is None else float(stored["t_s"]), sightings)


def _session(session: DeviceSession) -> dict[str, Any]:
    track, namer = session.track, session.namer
    state = track.state
    return {
        "map": map_digest(session.beacon_map),
        "captures": session.captures,
        "growths_px": list(session.growths_px),
        "last_rotation_wc": None if session.last_rotation_wc is None else _array(session.last_rotation_wc),
        "track": {
            "state": None
            if state is None
            else {
                "t_s": state.t_s,
                "mean": _array(state.mean),
                "covariance": _array(state.covariance),
                "outliers_in_row": state.outliers_in_row,
            },
            "accepted_in_row": track.accepted_in_row,
            "fixes": track.fixes,
            "outliers": track.outliers,
        },
        "panels": [
            {
                "relative_m": _array(panel.relative_m),
                "t_s": panel.t_s,
                "observations": [_observation(o) for o in panel.evidence.observations],
                "beacon_id": panel.beacon_id,
                "reading": None if panel.reading is None else panel.reading.model_dump(),
            }
            for panel in namer.panels
        ],
        "naming_stats": vars(namer.stats),
    }


def _read_session(stored: dict[str, Any], beacon_map: BeaconMap, rules: SessionRules) -> DeviceSession:
    session = DeviceSession(beacon_map, rules)
    session.captures = int(stored["captures"])
    session.growths_px = [float(g) for g in stored["growths_px"]]
    rotation = stored["last_rotation_wc"]
    session.last_rotation_wc = None if rotation is None else _read_array(rotation)
    kept = stored["track"]
    state = kept["state"]
    session.track = Track(
        rules.track,
        state=None
        if state is None
        else FilterState(
            float(state["t_s"]),
            _read_array(state["mean"]),
            _read_array(state["covariance"]),
            int(state["outliers_in_row"]),
        ),
        accepted_in_row=int(kept["accepted_in_row"]),
        fixes=int(kept["fixes"]),
        outliers=int(kept["outliers"]),
    )
    namer = session.namer
    for panel in stored["panels"]:
        evidence = namer.new_evidence()
        for observation in panel["observations"]:
            evidence.observations.append(_read_observation(observation))
        reading = panel["reading"]
        namer.panels.append(
            PanelTrack(
                relative_m=_read_array(panel["relative_m"]),
                t_s=float(panel["t_s"]),
                evidence=evidence,
                beacon_id=panel["beacon_id"],
                reading=None if reading is None else VlcReading.model_validate(reading),
            )
        )
    namer.stats = NamingStats(**{k: int(v) for k, v in stored["naming_stats"].items()})
    return session
