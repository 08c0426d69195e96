"""Survey photos for SurveyEndToEndTest: the quarter-scale office set of the Python survey tests
(`tests.helpers.survey_set`: hand-held frames from 1.2-1.6 m, tilted up to 30 degrees, each with
two or more panels, a compass reading with an indoor error, the panels in view labelled; the sketch
with every panel but the anchor a few centimetres off), written as `lumipose survey` reads them
(`simulator.survey.write_survey_fixtures`: frame_NN.json + .y, labels.json, sketch.json), with the
true map truth.json and set.json ({anchor, frames: [names]}) in the directory given.

usage: survey_photos.py OUT_DIR
"""

import json
import sys
from pathlib import Path

from simulator.survey import write_survey_fixtures
from tests.helpers import survey_set

out = Path(sys.argv[1])
truth, sketch, anchor, shots = survey_set()
frames, _, _ = write_survey_fixtures(out, list(shots), sketch)
(out / "truth.json").write_text(truth.model_dump_json(by_alias=True, exclude_none=True))
(out / "set.json").write_text(json.dumps({"anchor": anchor, "frames": [path.stem for path in frames]}))
