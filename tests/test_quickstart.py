"""docs/quickstart.md's researcher path, as a new user runs it, on a quarter-size rendered frame.

`tests/test_docs_commands.py` checks that every command and flag the page quotes exists; this runs
them: the map it shows is a valid map, a JPEG with the EXIF a phone writes is located with its
intrinsics stated, and the picture of what the pipeline saw is written.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from PIL import Image

from lumipose_cli.main import main
from shared_schemas import BeaconMap

QUICKSTART = Path(__file__).resolve().parents[1] / "docs" / "quickstart.md"


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", QUICKSTART.read_text(), re.S)


def test_the_map_the_quickstart_shows_is_a_valid_map():
    (text,) = _blocks("json")
    assert BeaconMap.model_validate(json.loads(text)).name == "my-panel"


def test_a_phone_photo_is_located_with_its_intrinsics_stated_and_pictured(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["render", "shot", "--position", "0.1", "0.2", "0", "--ypr", "5", "2", "-1", "--scale", "0.25",
                 "--png"]) == 0
    exif = Image.Exif()
    exif[0x010F], exif[0x0110] = "Xiaomi", "MI 8"  # Make, Model: what a Mi 8 writes
    Image.open("shot.png").convert("RGB").save("IMG_0001.jpg", quality=95, exif=exif)
    capsys.readouterr()

    assert main(["locate", "IMG_0001.jpg", "--map", "test-bench", "--annotate", "seen.png"]) == 0
    out = capsys.readouterr().out
    assert "from EXIF 'Xiaomi MI 8'" in out and "focal uncertainty 1.5 %" in out
    x, y = (float(v) for v in re.search(r"x=([-+.\d]+) m\s+y=([-+.\d]+) m", out).groups())
    # the photo's profile (the rear camera's datasheet) is not the render's (the front camera's): ~1 % off
    assert abs(x - 0.1) < 0.005 and abs(y - 0.2) < 0.005
    assert Image.open("seen.png").size[0] > 300

    assert main(["locate", "shot.json", "--annotate", "seen.png"]) == 0
    assert re.search(r"truth     error 2D 0\.\d\d mm", capsys.readouterr().out)
