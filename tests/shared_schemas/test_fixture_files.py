"""A fixture's format is the one of the file found beside its JSON (PNG signature or a raw plane)."""

import pytest

from shared_schemas import FrameFormat, FrameMeta
from shared_schemas.fixture_files import PNG_SIGNATURE, read_fixture_files, with_actual_format

META = {"width": 4, "height": 2, "camera": {"profile": "xiaomi-mi8-front"}}


@pytest.mark.parametrize(("said", "data", "read_as"), [
    ("Y8", PNG_SIGNATURE + b"rest", "PNG"),
    ("NV21", PNG_SIGNATURE + b"rest", "PNG"),
    ("PNG", bytes(8), "Y8"),
    ("NV21", bytes(12), "NV21"),
    ("PNG", PNG_SIGNATURE + b"rest", "PNG"),
])
def test_the_bytes_decide_between_png_and_a_raw_plane(said, data, read_as):
    meta = FrameMeta.model_validate({**META, "format": said})
    assert with_actual_format(meta, data).format is FrameFormat(read_as)


def test_read_fixture_files_finds_the_sibling_and_names_what_is_missing(tmp_path):
    (tmp_path / "frame.json").write_text(FrameMeta.model_validate(META).model_dump_json(by_alias=True))
    with pytest.raises(FileNotFoundError, match="frame.y, frame.yuv, frame.png"):
        read_fixture_files(tmp_path / "frame")
    (tmp_path / "frame.png").write_bytes(PNG_SIGNATURE + b"rest")
    for name in ("frame", "frame.json", "frame.png"):
        meta, data = read_fixture_files(tmp_path / name)
        assert meta.format is FrameFormat.png and data.startswith(PNG_SIGNATURE)
    with pytest.raises(FileNotFoundError, match="no frame metadata"):
        read_fixture_files(tmp_path / "other.y")
