"""Board specs as the server takes them, for BoardSpecTest: reads a JSON list of board.json texts from
the file given, writes a JSON list beside it (OUT) with, for each, null when the server's BoardSpec
accepts it, else the field its first error names ("" for the model as a whole).

usage: board_specs.py IN_JSON OUT_JSON
"""

import json
import sys
from pathlib import Path

from pydantic import ValidationError

from shared_schemas.calibration import BoardSpec

answers: list[str | None] = []
for text in json.loads(Path(sys.argv[1]).read_text()):
    try:
        BoardSpec.model_validate_json(text)
        answers.append(None)
    except ValidationError as e:
        answers.append(".".join(str(part) for part in e.errors()[0]["loc"]))
Path(sys.argv[2]).write_text(json.dumps(answers))
