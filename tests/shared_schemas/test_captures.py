"""Frames listed as shot, sent as the app sends its captures: a burst's ID frames, then its pose frame."""

from shared_schemas import FrameKind
from shared_schemas.captures import bursts_in_upload_order

P, I = FrameKind.pose, FrameKind.id


def test_each_capture_sends_its_id_frames_before_its_pose_frame():
    assert bursts_in_upload_order([P, I, I, P, I, P]) == [[1, 2, 0], [4, 3], [5]]


def test_id_frames_before_any_pose_frame_and_pose_frames_alone():
    assert bursts_in_upload_order([I, I, P, P]) == [[0, 1], [2], [3]]
    assert bursts_in_upload_order([]) == []
