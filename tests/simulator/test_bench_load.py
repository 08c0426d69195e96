"""`lumipose bench load --url`: a running service (here the session's), not a server of its own."""

import json

from lumipose_cli.main import main


def test_bench_load_against_a_running_service(server_url, capsys):
    argv = ["bench", "load", "--url", server_url, "--frames", "1080p", "--clients", "2", "--seconds", "0.5"]
    assert main([*argv, "--json"]) == 0
    (report,) = json.loads(capsys.readouterr().out)
    assert report["requests"] >= 2 and report["fixes"] == report["requests"] and report["errors"] == 0
    assert report["server_request_ms"] is None and report["server_peak_rss_mb"] is None  # not ours to measure
    assert main(["bench", "load", "--url", "http://127.0.0.1:9", "--clients", "1", "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["field"] == "url"
    assert main(["bench", "load", "--url", server_url, "--clients", "0"]) == 2
    assert "error: --clients must be at least 1" in capsys.readouterr().err


def test_bench_load_with_devices_and_a_watching_page(server_url, capsys):
    """An open page subscribed through the run gets the devices' events; the report counts them."""
    argv = ["bench", "load", "--url", server_url, "--frames", "1080p", "--clients", "1", "--seconds", "1",
            "--devices", "--watchers", "1", "--json"]
    assert main(argv) == 0
    (report,) = json.loads(capsys.readouterr().out)
    assert report["devices"] and report["watchers"] == 1 and report["errors"] == 0
    assert report["device_events"] >= 2  # the first one (every device) and at least one with load-0's frames
    assert report["device_updates"] >= 1 and report["event_kb"] > 0
    assert report["pictures"] + report["pictures_gone"] >= 1  # the frame view asked for load-0's newest picture
    assert main(["bench", "load", "--url", server_url, "--live-frames", "0", "--json"]) == 2
    assert json.loads(capsys.readouterr().out)["field"] == "live_frames"
