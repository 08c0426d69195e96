"""server/camera.py's intrinsics_from_profile for DeviceProfileTest: reads profiles.json
([{"profile": DeviceProfile, "width": w, "height": h}, ...]) from the directory given and writes
intrinsics.json ([{fx, fy, cx, cy, pixel_size_m}, ...]) beside it."""

import json
import sys
from pathlib import Path

from server.camera import intrinsics_from_profile
from shared_schemas import DeviceProfile

folder = Path(sys.argv[1])
out = []
for case in json.loads((folder / "profiles.json").read_text()):
    k = intrinsics_from_profile(DeviceProfile.model_validate(case["profile"]), case["width"], case["height"])
    out.append({"fx": k.fx, "fy": k.fy, "cx": k.cx, "cy": k.cy, "pixel_size_m": k.pixel_size_m})
(folder / "intrinsics.json").write_text(json.dumps(out))
