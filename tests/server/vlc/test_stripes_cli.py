"""`lumipose vlc stripes FRAME`: what it refuses, and when it says the frame looks turned."""

import io

import numpy as np
from PIL import Image

from lumipose_cli.main import main
from tests.server.test_photos import png_claiming


def stripes(capsys, frame, *extra: str) -> tuple[int, str]:
    code = main(["vlc", "stripes", str(frame), "--row-time-us", "20", "--exposure-s", "1e-4", *extra])
    captured = capsys.readouterr()
    return code, captured.out + captured.err


def png(pixels: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(pixels).save(buffer, "PNG")
    return buffer.getvalue()


def test_a_16_bit_png_is_refused_not_clipped(tmp_path, capsys):
    frame = tmp_path / "deep.png"
    frame.write_bytes(png(np.full((64, 64), 40000, np.uint16)))
    code, out = stripes(capsys, frame)
    assert code == 2 and "not 8-bit" in out, out


def test_an_oversized_header_is_refused_not_a_traceback(tmp_path, capsys):
    frame = tmp_path / "bomb.png"
    frame.write_bytes(png_claiming(30_000, 30_000))
    code, out = stripes(capsys, frame)
    assert code == 2 and "'bomb.png' has more than" in out and "megapixels" in out, out


def test_faint_column_texture_is_not_said_to_be_turned(tmp_path, capsys):
    """Plain rows, columns differing by 1 DN in 128: the columns' means step far more than the rows', but not
    like stripes (turned_frame_problem's min_relative_step)."""
    pixels = np.tile((128 + np.arange(200) // 2 % 2).astype(np.uint8), (200, 1))
    frame = tmp_path / "faint.png"
    frame.write_bytes(png(pixels))
    code, out = stripes(capsys, frame)
    assert code == 1 and out.startswith("no stripes") and "turned" not in out, out
    stripes_along_columns = np.tile(np.where(np.arange(200) // 10 % 2, 200, 40).astype(np.uint8), (200, 1))
    frame.write_bytes(png(stripes_along_columns))
    code, out = stripes(capsys, frame)
    assert code == 1 and "stripes run along columns" in out and "is the frame turned 90 degrees?" in out, out
