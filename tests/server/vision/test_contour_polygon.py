"""Blob rules and the polygon stage on drawn masks (exact shapes, integer pixels)."""

import cv2
import numpy as np
import pytest

from server.outcomes import Refusal
from server.vision.contour import Blob, PanelLook, find_beacon_blob
from server.vision.polygon import Quad, rounded_square_corners, square_corners
from shared_schemas import Beacon, FailureReason


def rounded_square_mask(size=400, side=200, radius=25, angle_deg=17.0, center=(200, 210)) -> np.ndarray:
    """A rotated rounded square drawn as a filled polygon, and its true corners."""
    h, r = side / 2, radius
    arcs = []
    for k, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        a = np.linspace(np.pi / 2 * k, np.pi / 2 * (k + 1), 20)
        arcs.append(np.column_stack([sx * (h - r) + r * np.cos(a), sy * (h - r) + r * np.sin(a)]))
    outline = np.concatenate(arcs)
    t = np.radians(angle_deg)
    rotation = np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])
    mask = np.zeros((size, size), np.uint8)
    cv2.fillPoly(mask, [np.round(outline @ rotation.T + center).astype(np.int32)], 255)
    corners = np.array([[h, h], [-h, h], [-h, -h], [h, -h]]) @ rotation.T + center
    return mask, corners


def test_rounded_square_is_accepted_and_its_corners_found_to_a_pixel():
    mask, truth = rounded_square_mask()
    blob = find_beacon_blob(mask)
    assert isinstance(blob, Blob)
    quad = rounded_square_corners(blob.contour)
    assert isinstance(quad, Quad)
    # every true corner has a found corner within 1.5 px (the polygon stage is the coarse guess)
    distances = np.linalg.norm(quad.corners[:, None] - truth[None], axis=2).min(axis=0)
    assert distances.max() < 1.5


def test_plain_rdp_misses_rounded_corners_the_paper_way():
    """Fig. 8a of the paper: RDP on a rounded square leaves the corners inside."""
    mask, truth = rounded_square_mask(radius=12)
    quad = square_corners(find_beacon_blob(mask).contour)
    assert isinstance(quad, Quad)
    assert np.linalg.norm(quad.corners[:, None] - truth[None], axis=2).min(axis=0).max() > 3.0
    # with the paper's own corner radius (11.5 % of the side) RDP does not even leave four
    refusal = square_corners(find_beacon_blob(rounded_square_mask(radius=25)[0]).contour)
    assert isinstance(refusal, Refusal) and "not 4" in refusal.message


def test_square_corner_path_finds_a_sharp_square():
    mask, truth = rounded_square_mask(radius=0.01)
    quad = square_corners(find_beacon_blob(mask).contour)
    assert isinstance(quad, Quad)
    assert np.linalg.norm(quad.corners[:, None] - truth[None], axis=2).min(axis=0).max() < 1.5


@pytest.mark.parametrize(
    "draw, reason, phrase",
    [
        (lambda m: cv2.circle(m, (200, 200), 90, 255, -1), FailureReason.not_a_square, "round lamp"),
        (lambda m: cv2.rectangle(m, (60, 150), (340, 250), 255, -1), FailureReason.not_a_square, "window"),
        (lambda m: cv2.fillPoly(m, [np.array([[60, 60], [340, 60], [340, 200], [200, 200], [200, 340], [60, 340]])], 255),
         FailureReason.not_a_square, "not convex"),
        (lambda m: cv2.rectangle(m, (100, 100), (103, 103), 255, -1), FailureReason.no_beacon, "no bright blob"),
    ],
    ids=["round-lamp", "window", "merged-panels", "speck"],
)
def test_blobs_that_are_not_the_beacon_are_refused_with_a_reason(draw, reason, phrase):
    mask = np.zeros((400, 400), np.uint8)
    draw(mask)
    refusal = find_beacon_blob(mask)
    assert isinstance(refusal, Refusal)
    assert refusal.reason is reason
    assert phrase in refusal.message


def test_a_blob_cut_by_the_border_is_kept_flagged_when_no_whole_panel_is_in_view():
    mask = np.zeros((400, 400), np.uint8)
    cv2.rectangle(mask, (0, 100), (150, 250), 255, -1)
    cut = find_beacon_blob(mask)
    assert isinstance(cut, Blob) and cut.cut
    cv2.rectangle(mask, (250, 250), (330, 330), 255, -1)  # a smaller whole panel wins over it
    whole = find_beacon_blob(mask)
    assert isinstance(whole, Blob) and not whole.cut and whole.bounding_box[0] == 250


def test_a_cut_blob_must_still_be_convex():
    mask = np.zeros((400, 400), np.uint8)
    cv2.fillPoly(mask, [np.array([[0, 60], [340, 60], [340, 200], [200, 200], [200, 340], [0, 340]])], 255)
    refusal = find_beacon_blob(mask)
    assert isinstance(refusal, Refusal) and refusal.reason is FailureReason.beacon_cut_off


@pytest.mark.parametrize(
    "beacon, draw",
    [
        (Beacon(id=0, center_m=[0, 0, 1], width_m=1.2, height_m=0.3), lambda m: cv2.rectangle(m, (60, 150), (340, 220), 255, -1)),
        (Beacon(id=0, center_m=[0, 0, 1], shape="circle", diameter_m=0.2), lambda m: cv2.circle(m, (200, 200), 90, 255, -1)),
    ],
    ids=["strip-panel", "downlight"],
)
def test_blobs_are_judged_by_the_map_panels_look(beacon, draw):
    mask = np.zeros((400, 400), np.uint8)
    draw(mask)
    assert isinstance(find_beacon_blob(mask, look=PanelLook.of(beacon)), Blob)
    assert isinstance(find_beacon_blob(mask), Refusal)  # not the paper's square panel


def test_a_square_is_not_a_round_downlight():
    mask, _ = rounded_square_mask()
    refusal = find_beacon_blob(mask, look=PanelLook.of(Beacon(id=0, center_m=[0, 0, 1], shape="circle", diameter_m=0.2)))
    assert isinstance(refusal, Refusal) and "round panel" in refusal.message


def test_beacon_beside_a_round_lamp_is_still_found():
    mask, _ = rounded_square_mask(size=600, center=(200, 300))
    cv2.circle(mask, (470, 300), 100, 255, -1)  # larger than the beacon
    blob = find_beacon_blob(mask)
    assert isinstance(blob, Blob)
    assert blob.bounding_box[0] < 350
