"""shared_schemas/capture_protocol.json is what the server and the client use, and is current."""

import json

from lumipose_cli.capture_protocol import PROTOCOL_PATH, PROTOCOL_SCHEMA, capture_protocol, rendered_protocol
from server.vlc.capture import id_frame_problem
from tests.helpers import dark_frame


def test_the_capture_protocol_file_is_current():
    assert PROTOCOL_PATH.exists() and PROTOCOL_PATH.read_text() == rendered_protocol(), (
        f"{PROTOCOL_PATH} is stale: run `python -m lumipose_cli.capture_protocol`"
    )


def test_the_file_parses_to_the_protocol():
    written = json.loads(PROTOCOL_PATH.read_text())
    assert written == capture_protocol() and written["schema"] == PROTOCOL_SCHEMA


def test_the_longest_id_exposure_is_the_one_the_server_still_reads():
    longest = capture_protocol()["id_max_exposure_s"]
    assert isinstance(longest, float)
    frame = dark_frame()
    at_limit = frame.meta.model_copy(update={"exposure_s": longest, "rolling_shutter_skew_s": 0.03, "timestamp_ns": 1})
    assert id_frame_problem(frame.__class__(frame.pixels, at_limit, frame.camera)) is None
    beyond = at_limit.model_copy(update={"exposure_s": longest * 1.01})
    assert "averaged away" in id_frame_problem(frame.__class__(frame.pixels, beyond, frame.camera))
