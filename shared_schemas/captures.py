"""Recorded frames sent the way the app sends its captures (docs/vlc.md, docs/android.md).

The app shoots a capture as a pose frame, then a burst of ID frames, and uploads the burst's ID
frames first, then its pose frame: a device's session keeps ID frames for its next pose frame.
`lumipose locate` and `lumipose client locate` take frames listed as shot and send them so, and
print what they got with the same helpers here (`print_outcome`, `write_picture`): the same verb prints
the same way on this machine and over HTTP, each frame in the order it was used.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from shared_schemas.cli import BadInput, number
from shared_schemas.models import BeaconMap, ErrorBody, FailureReason, FrameKind, GroundTruth, LocateResult

# The service's picture is a PNG (lossless: a contour's pixels stay as drawn); a name that asks for
# another format is refused rather than given PNG bytes under a .jpg name.
PICTURE_SUFFIX = ".png"
# How a photo's camera is asked for: the API's query parameters, and the client commands' flags for them.
PHOTO_CAMERA_QUERY = ("?profile=ID", "?camera=fx,fy,cx,cy")
PHOTO_CAMERA_FLAGS = ("--profile ID", "--camera fx,fy,cx,cy")


def bursts_in_upload_order(kinds: Sequence[FrameKind]) -> list[list[int]]:
    """The captures of frames listed as shot (indices into `kinds`), each in the order the app sends it.

    A capture is a pose frame and the ID frames listed after it (ID frames before the first pose
    frame are a capture of their own); within it, its ID frames go first, then its pose frame.
    """
    captures: list[list[int]] = []
    for index, kind in enumerate(kinds):
        if kind is FrameKind.pose or not captures:
            captures.append([index])
        else:
            captures[-1].append(index)
    return [capture[1:] + capture[:1] if kinds[capture[0]] is FrameKind.pose else capture for capture in captures]


def all_located(results: Sequence[LocateResult]) -> bool:
    """The commands' exit 0: some frame has a fix and every other one too, or is an ID frame kept for
    its session (`id_frame`: it has no fix of its own). One frame: its fix, as before."""
    kept = [result.ok or result.reason is FailureReason.id_frame for result in results]
    return all(kept) and any(result.ok for result in results)


def add_frame_series_arguments(parser: argparse.ArgumentParser) -> None:
    """`FRAME...`, `--beacon-id` and `--device`, as `lumipose locate` and `lumipose client locate` take them."""
    parser.add_argument(
        "frames",
        type=Path,
        nargs="+",
        metavar="FRAME",
        help="NAME.json, NAME.y, NAME.yuv or NAME.png, or a photo (JPEG, PNG without JSON, HEIC); several "
        "(a walk's, listed as shot) are located in turn, "
        "each capture's ID frames before its pose frame as the app sends them",
    )
    parser.add_argument(
        "--beacon-id",
        type=int,
        metavar="N",
        default=None,
        help="the map beacon the frames see, as the app may send it (default: none; the map or VLC tells)",
    )
    parser.add_argument(
        "--device",
        metavar="NAME",
        default=None,
        help="a device name: the frames go through its session (ID frames, tracking), as the app's do "
        "(default: none, each frame on its own)",
    )


def annotation_path(annotate: Path, frame_path: Path, several: bool) -> Path:
    """Where `--annotate PNG` puts a frame's picture: PNG itself for one frame; for several, one each
    beside it, named PNG's stem, '-', the frame's stem."""
    return annotate.with_name(f"{annotate.stem}-{frame_path.stem}{PICTURE_SUFFIX}") if several else annotate


def annotation_paths(annotate: Path | None, frames: Sequence[Path]) -> list[Path | None]:
    """Each frame's picture for `--annotate PNG` (`annotation_path`), or None without the flag. Two frames
    whose pictures would land on one file (a/x.json and b/x.json) are refused before any work."""
    if annotate is None:
        return [None] * len(frames)
    if annotate.suffix.lower() != PICTURE_SUFFIX:
        raise BadInput(
            f"--annotate {annotate}: the picture is a PNG; give a name ending in {PICTURE_SUFFIX}", field="annotate"
        )
    pictures = [annotation_path(annotate, frame, several=len(frames) > 1) for frame in frames]
    seen: dict[Path, Path] = {}
    for frame, picture in zip(frames, pictures, strict=True):
        if picture in seen:
            raise BadInput(
                f"--annotate: {seen[picture]} and {frame} would both write {picture} (frames with one name)",
                field="annotate",
            )
        seen[picture] = frame
    return list(pictures)


def write_picture(path: Path, png: bytes) -> None:
    """Write a frame's `--annotate` picture and say where (on stderr: stdout stays the result alone, as --json
    needs it); BadInput (field annotate) when it cannot be written."""
    try:
        path.write_bytes(png)
    except OSError as error:
        raise BadInput(f"cannot write the picture {path}: {error.strerror or error}", field="annotate") from None
    print(f"picture: {path}", file=sys.stderr)


def print_outcome(
    name: str,
    outcome: LocateResult | ErrorBody,
    truth: GroundTruth | None,
    *,
    as_json: bool,
    several: bool,
    beacon_map: BeaconMap | None = None,
) -> None:
    """What `locate` and `client locate` print of one frame: the contract's result (or the error body of a
    frame that could not be read) as JSON, or for people a few lines (one frame) or one line named `name`
    (one of several). `truth`: the frame's ground truth, for the error against it; `beacon_map`: the map
    located in, for what the focal uncertainty means at the fix's distance."""
    if as_json:
        print(outcome.model_dump_json(by_alias=True, indent=None if several else 2))
    elif isinstance(outcome, ErrorBody):
        print(f"{name}  error: {outcome.message}")
    elif several:
        print_line(name, outcome, truth)
    else:
        print_result(outcome, truth, beacon_map)


def print_result(result: LocateResult, truth: GroundTruth | None, beacon_map: BeaconMap | None) -> None:
    """A frame's result in a few lines for people: the intrinsics used and how sure they are, the fix (and its
    error against the frame's ground truth when it has one), or the reason there is none."""
    if result.camera_used is not None:
        print_camera_used(result, beacon_map)
    if not result.ok:
        print(f"no fix: {result.reason}: {result.message}")
        return
    assert result.position_m is not None and result.yaw_pitch_roll_deg is not None  # a fix sets both
    x, y, z = result.position_m
    yaw, pitch, roll = result.yaw_pitch_roll_deg
    print(f"position  x={x:+.4f} m  y={y:+.4f} m  z={z:+.4f} m   (beacon {result.beacon_id})")
    print(
        f"attitude  yaw={yaw:+.2f}  pitch={pitch:+.2f}  roll={roll:+.2f} deg"
        f"   gravity prior {'used' if result.gravity_used else 'not used'}"
    )
    # an outline fit (a cut panel, a rectangle, a circle) has no square's two poses to compare
    ambiguity = "n/a" if result.ambiguity_ratio is None else number(result.ambiguity_ratio)
    reprojection = "n/a" if result.reprojection_error_px is None else f"{number(result.reprojection_error_px, 3)} px"
    total_ms = result.timing_ms.get("total")  # the contract's timings are for people, not required
    took = "time n/a" if total_ms is None else f"{total_ms:.1f} ms"
    print(f"quality   reprojection {reprojection}, ambiguity ratio {ambiguity}, {took}")
    errors = truth_errors_mm(result.position_m, truth)
    if errors is not None:
        print(f"truth     error 2D {errors[0]:.2f} mm, 3D {errors[1]:.2f} mm")
    for warning in result.warnings:
        print(f"warning   {warning}")


def print_camera_used(result: LocateResult, beacon_map: BeaconMap | None) -> None:
    """Which intrinsics a frame was located with, and what their focal uncertainty means at the fix's distance
    (a relative focal error scales the distance along the ray by as much)."""
    k = result.camera_used
    assert k is not None  # print_result checks
    print(f"camera    fx={k.fx:.1f} fy={k.fy:.1f} cx={k.cx:.1f} cy={k.cy:.1f} px from {k.detail}")
    sigma = k.focal_sigma_rel
    if sigma is None:
        print("          focal uncertainty unknown (intrinsics as given, not checked here)")
        return
    line = f"          focal uncertainty {100 * sigma:.2g} %"
    beacon = beacon_map.beacon(result.beacon_id) if beacon_map and result.beacon_id is not None else None
    if result.position_m is not None and beacon is not None:
        distance_m = math.dist(result.position_m, beacon.center_m)
        line += f", about {1000 * sigma * distance_m:.1f} mm along the ray at this fix's {distance_m:.2f} m"
    print(line)


def print_line(name: str, result: LocateResult, truth: GroundTruth | None) -> None:
    """One frame of several on one line: its name and fix (or reason)."""
    if not result.ok:
        print(f"{name}  no fix: {result.reason}: {result.message}")
        return
    assert result.position_m is not None  # a fix sets it
    x, y, z = result.position_m
    errors = truth_errors_mm(result.position_m, truth)
    error = "" if errors is None else f"  truth error 2D {errors[0]:.1f} mm"
    warnings = "".join(f"  warning: {warning}" for warning in result.warnings)  # still one line a frame
    print(f"{name}  x={x:+.4f} y={y:+.4f} z={z:+.4f} m  beacon {result.beacon_id}{error}{warnings}")


def truth_errors_mm(position_m: Sequence[float], truth: GroundTruth | None) -> tuple[float, float] | None:
    """The fix's 2-D and 3-D distance from the frame's ground truth, in mm; None for a frame without one."""
    if truth is None:
        return None
    return 1000 * math.dist(position_m[:2], truth.position_m[:2]), 1000 * math.dist(position_m, truth.position_m)
