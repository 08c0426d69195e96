"""Round LEDs blinking fully off, as a phone's rolling shutter shows them (issue 29, the Luxapose photos of
lab11/vlc-localization: ~21 us a row, 60 us exposures, 1-4 kHz LEDs ~100 px across in a 33 MP frame whose
coarse view keeps every 9th row). Drawn here, since the photos have no licence: a saturated disc with a
wide dim halo (the bloom of a small bright source), each row lit by the share of its exposure the LED is
on, thresholded at the photos' own levels (background 0, plateau 56 DN: the 0.02 % quantile of a 33 MP
frame with five small LEDs falls in their halos, so the blobs' edges lie on the halos' shallow slopes)."""

from dataclasses import replace

import cv2
import numpy as np

from server.ingest import LumaFrame
from server.vision.beacons import CandidateRules, Candidates, find_beacon_blobs
from server.vision.binarize import Levels
from server.vision.roi import FrameView
from server.vlc.capture import stripe_gap_rows
from server.vlc.reader import read_id_frame
from simulator.bench_real_leds import EXPOSURE_S, ROW_RATE_HZ, id_frame

ROW_S = 1 / ROW_RATE_HZ  # the Lumia 1020's row time (lab11's phones/cameras/lumia_1020_back.py); exposure 2.9 rows
HEIGHT, WIDTH = 540, 720
COARSE = CandidateRules(coarse_short_side_px=60)  # step 9, as a 33 MP photo's at the contract's 480
PHOTO_LEVELS = FrameView(levels=Levels(background=0.0, plateau=56.0))


def _frame(centres: list[tuple[float, float]], frequency_hz: float, seed: int, turned: bool = False) -> LumaFrame:
    """LEDs at `centres` (x, y): a 22 px disc blurred by 4 px at 600 DN (clipped) and a halo of 60 DN
    (a 25 px Gaussian), square waves at `frequency_hz`, 50 % duty, fully off; the first row's phase random;
    `turned`: the frame transposed, its stripes along the columns (a portrait photo as stored)."""
    rng = np.random.default_rng(seed)
    ys, xs = np.mgrid[0:HEIGHT, 0:WIDTH].astype(float)
    disc = np.zeros((HEIGHT, WIDTH))
    for cx, cy in centres:
        disc[np.hypot(xs - cx, ys - cy) <= 22.0] = 1.0
    halo = cv2.GaussianBlur(disc, (0, 0), 25.0)
    image = 600.0 * cv2.GaussianBlur(disc, (0, 0), 4.0) + 60.0 * halo / halo.max()
    # each row's share of its exposure window during which the LED is on
    t = np.arange(HEIGHT)[:, None] * ROW_S + rng.uniform(0, 1 / frequency_hz) + np.linspace(0, EXPOSURE_S, 64)
    on = (np.mod(t * frequency_hz, 1.0) < 0.5).mean(axis=1)
    pixels = np.clip(np.round(image * on[:, None] + rng.normal(0.0, 1.5, image.shape)), 0, 255).astype(np.uint8)
    return id_frame(pixels.T if turned else pixels)


def _blobs(frame: LumaFrame) -> Candidates:
    """The frame's blobs at the photos' levels, its dark rows bridged (as `server.vlc.capture.frame_blobs`)."""
    return find_beacon_blobs(frame.pixels, COARSE, replace(PHOTO_LEVELS, stripe_gap_rows=stripe_gap_rows(frame)))


def test_a_small_round_led_s_comb_is_one_blob_though_the_coarse_view_steps_its_rows():
    # the rows the view keeps fall on bars' middles or their smeared ends, so each is as wide as its phase
    # in a bar makes the halo: the outline steps by a view pixel a row (1289590: 4 of these 12 refused)
    for frequency_hz in (1000.0, 2000.0, 3000.0, 4000.0):
        for seed in range(3):
            found = _blobs(_frame([(360.0, 270.0)], frequency_hz, seed + int(frequency_hz)))
            assert len(found.blobs) == 1, (frequency_hz, seed, found.rejected)
            (blob,) = found.blobs
            assert not blob.cut_off
            x, y, w, h = blob.bounding_box
            assert abs(x + w / 2 - 360) < 12 and abs(y + h / 2 - 270) < 12, blob.bounding_box


def test_a_turned_round_led_keyed_fully_off_says_it_looks_turned():
    # its full-resolution mask is one upright bar of the comb, whose columns are smooth: the blob's box is
    # judged instead (1289590: read with no problem or not found, as lab11's portrait photos as stored)
    for frequency_hz in (2000.0, 3000.0):
        frame = _frame([(270.0, 360.0)], frequency_hz, seed=int(frequency_hz), turned=True)
        reading = read_id_frame(frame, COARSE, found=_blobs(frame))
        assert reading.problem is not None and "turned" in reading.problem, (frequency_hz, reading)
    upright = _frame([(360.0, 270.0)], 3000.0, seed=3)
    assert read_id_frame(upright, COARSE, found=_blobs(upright)).problem is None
