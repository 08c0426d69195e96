"""Time and memory of reading a large phone photo (issue 29): `python -m simulator.bench_photo_decode [--json]`.

A JPEG of each size (12000 x 9000 = 108 MP by default, as Samsung's and Xiaomi's 108 MP modes write) is made
from a real photo (tests/fixtures/real_photos, CC-BY-SA-4.0) blown up with sensor-like noise, so its entropy-coded
data is a phone's size, not a flat grey's. Each is then read by `server.photos.read_photo` in a fresh Python
process, whose peak resident memory (VmHWM, reset before the read) less its resident memory then is the decode's.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

SOURCE = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "real_photos" / "exif-jpg_tests_22-canon_tags.jpg"
SIZES = {"108mp": (12000, 9000), "50mp": (8160, 6120), "200mp": (16320, 12240)}

_CHILD = """
import json, re, sys, time
from pathlib import Path
import server.photos as photos

def hwm_mb():
    return int(re.search(r"VmHWM:\\s+(\\d+) kB", Path("/proc/self/status").read_text())[1]) / 1024

data = Path(sys.argv[1]).read_bytes()
Path("/proc/self/clear_refs").write_text("5")  # the peak resident size starts again from the current one
before = hwm_mb()
start = time.perf_counter()
photo = photos.read_photo(data, Path(sys.argv[1]).name)
seconds = time.perf_counter() - start
peak = hwm_mb()
print(json.dumps({"seconds": seconds, "decode_peak_mb": peak - before, "process_peak_mb": peak,
                  "luma_mb": photo.pixels.nbytes / 2**20, "reduction": photo.reduction,
                  "decoded": list(photo.pixels.shape[::-1]), "bytes": len(data)}))
"""


def make_jpeg(size: tuple[int, int], path: Path, quality: int = 92, seed: int = 1) -> None:
    """A real photo blown up to `size` (width, height) with noise of a phone's sensor at base ISO (sigma 2)."""
    photo = cv2.imread(str(SOURCE), cv2.IMREAD_COLOR)
    big = cv2.resize(photo, size, interpolation=cv2.INTER_CUBIC)
    noise = np.random.default_rng(seed).normal(0, 2, size=(size[1], size[0], 1)).astype(np.float32)
    big = np.clip(big + noise, 0, 255).astype(np.uint8)
    cv2.imwrite(str(path), big, [cv2.IMWRITE_JPEG_QUALITY, quality])


def bench(names: list[str]) -> list[dict]:
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name in names:
            path = Path(folder) / f"{name}.jpg"
            make_jpeg(SIZES[name], path)
            out = subprocess.run([sys.executable, "-c", _CHILD, str(path)], capture_output=True, text=True, check=True)
            rows.append({"photo": name, "size": list(SIZES[name]), **json.loads(out.stdout)})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", nargs="+", choices=sorted(SIZES), default=["108mp"])
    parser.add_argument("--json", action="store_true", help="the figures as JSON")
    args = parser.parse_args(argv)
    rows = bench(args.sizes)
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    for row in rows:
        width, height = row["size"]
        print(
            f"{row['photo']}: {width}x{height} JPEG of {row['bytes'] / 1e6:.1f} MB -> {row['decoded'][0]}x"
            f"{row['decoded'][1]} luma (1/{row['reduction']}, {row['luma_mb']:.1f} MB) in {row['seconds']:.2f} s, "
            f"decode peak +{row['decode_peak_mb']:.0f} MB (process {row['process_peak_mb']:.0f} MB)"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
