"""`lumipose bench negatives`: real photos of rooms, ceilings and lamps, none of a Lumipose panel.

Every photo of `simulator/negatives/photos/manifest.json` (the shipped ones, and with `--local` the
ones whose licence keeps them out of the repository, fetched as the manifest says) is located with
a bundled profile against the bundled panels (the test bench's and the scenes' 174 mm square at
1.0, 2.72 and 3.0 m, with the first beacon named where a map has several, as the app may send it;
the shapes bench's 600 mm square and 1200 x 300 mm rectangle) at each `required_sigma_m`: any fix
is a wrong one. A refusal at one sigma is one at every smaller sigma too (the gates only tighten),
so only a fix is tried again at the next one down.
"""

from __future__ import annotations

import json
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from shared_schemas import BeaconMap

PHOTOS = Path(__file__).parent / "negatives" / "photos"
SIGMAS_M = (0.01, 0.05, 0.1, 0.5, 1.0)
PROFILE = "xiaomi-mi8-rear"


def bench_maps() -> dict[str, BeaconMap]:
    """The panels the photos are located against, by name."""
    from shared_schemas.cli import read_map_argument
    from simulator.bench_shapes import shape_cases
    from simulator.scene import find_scene

    maps = {"test-bench": read_map_argument("test-bench", None)}
    for name in ("office", "android-bench"):  # paper-bench, walk-one-panel, office-9: the same panel at these heights
        maps[name] = find_scene(name).beacon_map()
    for key in ("square-600", "rectangle-1200x300"):
        maps[key] = BeaconMap(name=key, beacons=[shape_cases()[key].beacon])
    return maps


def photo_rows(path: Path, sigmas_m: tuple[float, ...] = SIGMAS_M) -> list[dict]:
    """One row per (map, sigma) of the photo at `path`."""
    from server.camera import resolve_profile_args
    from server.ingest import read_photo_file
    from server.locator import locate

    profiles, profile = resolve_profile_args([PROFILE])
    frame = read_photo_file(path, profiles, None, profile)[0]
    rows: list[dict] = []
    for name, beacon_map in bench_maps().items():
        beacon_id = beacon_map.beacons[0].id if len(beacon_map.beacons) > 1 else None
        refused = None
        for sigma in sorted(sigmas_m, reverse=True):
            if refused is None:
                asked = beacon_map.model_copy(update={"required_sigma_m": sigma})
                result = locate(frame, asked, beacon_id=beacon_id)
                ok, reason = result.ok, None if result.ok else str(result.reason)
                message = (result.warnings[0] if result.warnings else "") if result.ok else result.message or ""
                if not ok:
                    refused = reason
            else:
                ok, reason, message = False, refused, "refused at a larger sigma"
            rows.append({"photo": path.name, "map": name, "sigma_m": sigma, "ok": ok, "reason": reason,
                         "message": message[:200]})  # fmt: skip
    return rows


def run_negatives(local: Path | None = None, workers: int = 2, sigmas_m: tuple[float, ...] = SIGMAS_M) -> dict:
    """Locate every photo of the manifest found here (and in `local`); the fixes by map and sigma."""
    entries = json.loads((PHOTOS / "manifest.json").read_text())["photos"]
    paths = []
    for entry in entries:
        where = PHOTOS if entry["shipped"] else local
        if where is not None and (where / entry["file"]).is_file():
            paths.append(where / entry["file"])
    start = time.perf_counter()
    with ProcessPoolExecutor(max(1, workers)) as pool:
        rows = [row for rows in pool.map(photo_rows, paths, [sigmas_m] * len(paths)) for row in rows]
    fixes = [row for row in rows if row["ok"]]
    return {
        "photos": len(paths),
        "listed": len(entries),
        "locates": len(rows),
        "fixes": len(fixes),
        "fixes_by_map_sigma": {
            f"{m} {s:g}": n for (m, s), n in sorted(Counter((r["map"], r["sigma_m"]) for r in fixes).items())
        },
        "photos_with_fixes": sorted({r["photo"] for r in fixes}),
        "reasons": dict(Counter(r["reason"] or "fix" for r in rows).most_common()),
        "wall_s": round(time.perf_counter() - start, 1),
        "rows": rows,
    }


def format_negatives(report: dict) -> str:
    lines = [f"{report['photos']} of {report['listed']} photos, {report['locates']} locates, {report['fixes']} fixes "
             f"({report['wall_s']:.0f} s)"]  # fmt: skip
    lines += [f"  fixes {key}: {count}" for key, count in report["fixes_by_map_sigma"].items()]
    lines += [f"  photo with fixes: {name}" for name in report["photos_with_fixes"]]
    lines.append("  outcomes: " + ", ".join(f"{k} {v}" for k, v in report["reasons"].items()))
    return "\n".join(lines)
