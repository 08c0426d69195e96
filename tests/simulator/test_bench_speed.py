"""`lumipose bench speed` plumbing: one small run's report, and the table and figure drawn from a report
(the figures themselves are CLI runs: docs/performance.md)."""

import json

import pytest

from lumipose_cli.main import main
from simulator.bench_speed import PATHS, TARGETS, format_speed, id_window, markdown_table, plot_speed
from simulator.cli import SPEED_PATHS

ROW_FIELDS = {"path", "variant", "label", "target_ratio", "median_ratio", "round_median_ratios", "p90_ratio",
              "median_ms", "reference_median_ms", "refusals", "frames", "calls", "met", "cpu_median_ratio",
              "cpu_round_median_ratios"}


def _report(ratios: dict[tuple[str, str], float]) -> dict:
    rows = [{"path": path, "variant": variant, "label": TARGETS[(path, variant)].label,
             "target_ratio": TARGETS[(path, variant)].ratio, "median_ratio": ratio, "round_median_ratios": [ratio],
             "p90_ratio": ratio, "cpu_median_ratio": ratio, "median_ms": 5.0 * ratio, "reference_median_ms": 5.0,
             "refusals": 0, "frames": 1, "calls": 1, "met": ratio <= TARGETS[(path, variant)].ratio}
            for (path, variant), ratio in ratios.items()]
    return {"rows": rows, "config": {"frames": 1, "rounds": 1, "repeats": 1, "distances_m": [1.0]},
            "machine": {"cpu_count": 2, "load_average_1min": 1.0, "commit": "abc1234"}}


def test_the_command_line_knows_every_path():
    assert SPEED_PATHS == PATHS


def test_a_small_run_reports_its_path_beside_the_target(capsys):
    assert main(["bench", "speed", "--path", "square-quarter", "--frames", "1", "--rounds", "2", "--distance", "1",
                 "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    (row,) = report["rows"]
    assert set(row) >= ROW_FIELDS
    assert (row["path"], row["variant"], row["target_ratio"]) == ("square-quarter", "quarter", 1.0)
    assert len(row["round_median_ratios"]) == 2 and row["calls"] == 2 and row["refusals"] == 0
    assert row["median_ratio"] > 0 and report["machine"]["cpu_count"] >= 1


def test_the_markdown_table_takes_before_from_a_baseline_and_after_from_the_report():
    before = _report({("square", "full"): 5.0, ("cut", "full"): 80.0})
    after = _report({("square", "full"): 1.5})
    lines = markdown_table(after, before).splitlines()
    assert lines[0] == "| path | issue 30 (quiet) | before (wall / CPU) | target | after (wall / CPU) | met |"
    assert len(lines) == 2 + len(TARGETS)
    assert "| whole square, full resolution | 4.4-5.4x | 5.00x / 5.00x | <= 2.00x | 1.50x / 1.50x | yes |" in lines
    assert "| cut panel, full | 80x | 80.0x / 80.0x | <= 8.00x | - | - |" in lines
    assert "| cut panel, quarter | 55x | - | <= 8.00x | - | - |" in lines


def test_the_readable_table_and_the_figure_come_from_a_report(tmp_path):
    report = _report({("square", "full"): 1.5, ("rectangle", "full"): 282.0})
    text = format_speed(report)
    assert "whole square, full resolution" in text and "282.0x" in text
    plot_speed(report, tmp_path / "speed.png", before=_report({("square", "full"): 5.0}))
    assert (tmp_path / "speed.png").stat().st_size > 10_000


@pytest.mark.parametrize(("window", "grown"), [((100, 200, 300, 400), (80, 150, 320, 450)),
                                               ((0, 10, 50, 990), (0, 0, 55, 1000)),
                                               ((0, 0, 33, 33), (0, 0, 37, 42))])  # rounded up, as the app's
def test_an_id_window_is_its_pose_window_grown_as_the_app_grows_it(window, grown):
    assert id_window(window, 1000, 1000) == grown
