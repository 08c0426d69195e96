"""An ID frame cut to a window (the contract's `crop`) reads the same stripes at the same times."""

import numpy as np

from server.ingest import LumaFrame
from server.vlc.reader import read_id_frame
from shared_schemas import Crop
from tests.server.vlc.conftest import id_frames


def test_cropped_id_frame_gives_the_same_observation():
    (frame,) = id_frames(beacon_id=42, distance_m=1.2, exposure_s=1 / 8000, count=1, seed=4)
    (panel,) = read_id_frame(frame).panels
    x, y, w, h = panel.blob.bounding_box
    x0, y0, x1, y1 = x - w, y - h, x + 2 * w, y + 2 * h
    meta = frame.meta.model_copy(update={
        "width": x1 - x0, "height": y1 - y0,
        "crop": Crop(x=x0, y=y0, full_width=frame.meta.width, full_height=frame.meta.height)})
    camera = frame.camera.model_copy(update={"cx": frame.camera.cx - x0, "cy": frame.camera.cy - y0})
    (cropped,) = read_id_frame(LumaFrame(frame.pixels[y0:y1, x0:x1], meta, camera)).panels
    np.testing.assert_allclose(cropped.centroid_norm, panel.centroid_norm, atol=2e-4)
    def row_times_s(observation):  # when each sampled row started its exposure
        return observation.timestamp_s + observation.row_offsets_s

    # the window's own threshold may move the panel's first row by one: the rows' times must lie on
    # the full frame's row grid and cover the same span
    row_time_s = frame.meta.rolling_shutter_skew_s / (frame.meta.height - 1)
    rows = (row_times_s(cropped.observation) - row_times_s(panel.observation)[0, 0]) / row_time_s
    np.testing.assert_allclose(rows, np.round(rows), atol=1e-3)
    assert abs(rows[0, 0]) < 1.5 and abs(rows[-1, -1] - (row_times_s(panel.observation)[-1, -1]
                                                         - row_times_s(panel.observation)[0, 0]) / row_time_s) < 4.5
