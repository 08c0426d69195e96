"""Export the contract's JSON Schemas: `python -m shared_schemas.export`.

A test fails when the files in `json/` differ from what this would write.
"""

from __future__ import annotations

import json
from pathlib import Path

from pydantic import BaseModel

from shared_schemas.calibration import BoardSpec, BoardView, CalibrationReport, CalibrationRequest
from shared_schemas.models import BeaconMap, DeviceProfile, ErrorBody, FrameMeta, LocateResult
from shared_schemas.survey import SurveyReport, SurveyRequest

SCHEMA_DIR = Path(__file__).parent / "json"
EXPORTED: dict[str, type[BaseModel]] = {
    "frame": FrameMeta,
    "map": BeaconMap,
    "device_profile": DeviceProfile,
    "result": LocateResult,
    "error": ErrorBody,
    "board": BoardSpec,
    "board_view": BoardView,
    "calibration_request": CalibrationRequest,
    "calibration_report": CalibrationReport,
    "survey_request": SurveyRequest,
    "survey_report": SurveyReport,
}


def rendered_schemas() -> dict[str, str]:
    """File name -> JSON text of every exported schema."""
    return {
        f"{name}.schema.json": json.dumps(model.model_json_schema(by_alias=True), indent=2) + "\n"
        for name, model in EXPORTED.items()
    }


def main() -> None:
    SCHEMA_DIR.mkdir(exist_ok=True)
    for file_name, text in rendered_schemas().items():
        (SCHEMA_DIR / file_name).write_text(text)
        print(f"wrote {SCHEMA_DIR / file_name}")


if __name__ == "__main__":
    main()
