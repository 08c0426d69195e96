"""Export the service's OpenAPI spec to shared_schemas/openapi.json: `python -m server.api.openapi`.

A test fails when the file differs from what the app serves; the Android client and other
clients are written against the file.
"""

from __future__ import annotations

import json
from pathlib import Path

from server.api.config import Settings
from server.api.main import create_app
from shared_schemas import PACKAGE_DIR

OPENAPI_PATH = PACKAGE_DIR / "openapi.json"


def rendered_openapi() -> str:
    spec = create_app(Settings(data_dir=Path("unused"))).openapi()
    spec["info"]["version"] = "1"  # the API's version, not the package's: the file changes with the API only
    return json.dumps(spec, indent=2, sort_keys=True) + "\n"


def main() -> None:
    OPENAPI_PATH.write_text(rendered_openapi())
    print(f"wrote {OPENAPI_PATH}")


if __name__ == "__main__":
    main()
