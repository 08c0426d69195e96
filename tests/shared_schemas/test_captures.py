"""Frames listed as shot, sent as the app sends its captures: a burst's ID frames, then its pose frame."""

from shared_schemas import FrameKind
from shared_schemas.captures import all_located, bursts_in_upload_order

P, I = FrameKind.pose, FrameKind.id


def test_each_capture_sends_its_id_frames_before_its_pose_frame():
    assert bursts_in_upload_order([P, I, I, P, I, P]) == [[1, 2, 0], [4, 3], [5]]


def test_id_frames_before_any_pose_frame_and_pose_frames_alone():
    assert bursts_in_upload_order([I, I, P, P]) == [[0, 1], [2], [3]]
    assert bursts_in_upload_order([]) == []


def test_a_series_is_located_when_every_frame_has_a_fix_or_was_kept_for_its_session():
    from shared_schemas import FailureReason, LocateResult

    fix = LocateResult(ok=True, position_m=[0, 0, 1], yaw_pitch_roll_deg=[0, 0, 0], beacon_id=1)
    kept = LocateResult(ok=False, reason=FailureReason.id_frame, message="ID frame kept")
    lost = LocateResult(ok=False, reason=FailureReason.unknown_beacon, message="no ID")
    assert all_located([kept, kept, fix])
    assert not all_located([kept, lost, fix])
    assert not all_located([kept])  # one ID frame alone: no fix, as before


def test_annotation_paths_one_picture_per_frame_and_no_two_on_one_file():
    from pathlib import Path

    import pytest

    from shared_schemas.captures import annotation_paths
    from shared_schemas.cli import BadInput

    assert annotation_paths(None, [Path("a.json")]) == [None]
    assert annotation_paths(Path("out/seen.png"), [Path("a.json")]) == [Path("out/seen.png")]
    assert annotation_paths(Path("out/seen.png"), [Path("w/a.json"), Path("w/b.json")]) == [
        Path("out/seen-a.png"),
        Path("out/seen-b.png"),
    ]
    with pytest.raises(BadInput) as refused:
        annotation_paths(Path("seen.png"), [Path("a/x.json"), Path("b/x.json")])
    assert refused.value.body.field == "annotate" and "a/x.json and b/x.json" in str(refused.value)


def test_a_walks_line_carries_the_results_warnings(capsys):
    from shared_schemas import LocateResult
    from shared_schemas.captures import print_line

    result = LocateResult(ok=True, position_m=[0.1, 0.2, -2.4], beacon_id=0, warnings=["the camera is 2.40 m below"])
    print_line("f.json", result, None)
    (line,) = capsys.readouterr().out.splitlines()  # one line a frame, its warnings on it
    assert line.endswith("beacon 0  warning: the camera is 2.40 m below")


def test_a_summary_without_timings_prints_and_does_not_crash(capsys):
    from shared_schemas import LocateResult
    from shared_schemas.captures import print_result

    result = LocateResult(ok=True, position_m=[0.1, 0.2, 0.0], yaw_pitch_roll_deg=[0.0, 0.0, 0.0], beacon_id=0)
    print_result(result, None, None)  # timing_ms defaults to {} in the contract
    assert "time n/a" in capsys.readouterr().out
