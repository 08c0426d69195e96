"""Every plot type on tiny synthetic results (no renders): each writes a PNG that decodes, and draws what it says."""

import json
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from lumipose_cli.main import main
from shared_schemas.api import Evaluation, EvaluationRow
from simulator.bench_fidelity import plot_fidelity
from simulator.bench_office import plot_walk
from simulator.bench_partial import plot_partial
from simulator.bench_vlc import plot_cut, plot_vlc
from simulator.cli import plot_sample_evaluation
from simulator.reports import Outcome, nice_length, plot_heatmap, plot_scatter, plot_sweep

RESULTS = Path(__file__).parents[2] / "docs" / "results"


def _decodes(path: Path) -> tuple[int, int]:
    with Image.open(path) as image:
        image.load()
        return image.size


def _outcome(index: int, x: float, y: float, error_mm: float | None) -> Outcome:
    estimate = None if error_mm is None else (x + error_mm / 1000, y, 0.0)
    return Outcome(index=index, label=f"{index}", true_m=(x, y, 0.0), estimate_m=estimate,
                   reason=None if estimate else "no_beacon", message=None, reprojection_px=None)


def _grid(cells: int = 5, cell_m: float = 0.05) -> np.ndarray:
    return np.array([(i * cell_m, j * cell_m) for j in range(cells) for i in range(cells)])


def test_a_partial_run_heat_map_tells_not_run_from_no_fix(tmp_path):
    planned = _grid()
    run = [_outcome(0, 0.0, 0.0, 1.0), _outcome(1, 0.1, 0.1, None), _outcome(2, 0.2, 0.2, 2.0)]
    counts = plot_heatmap(run, tmp_path / "heat.png", "partial", 0.05, planned)
    assert counts == {"run": 3, "no_fix": 1, "not_run": 22}
    assert _decodes(tmp_path / "heat.png")[0] > 400
    pixels = np.asarray(Image.open(tmp_path / "heat.png").convert("RGB")).reshape(-1, 3).astype(int)
    red = (pixels[:, 0] > 180) & (pixels[:, 1] < 60) & (pixels[:, 2] < 60)  # tab:red, the no-fix cell
    assert 200 < red.sum() < 30_000  # one cell of 25 (and its legend swatch), not the whole map


def test_heat_map_cells_are_the_given_cell_not_the_gaps_between_samples(tmp_path):
    far_apart = [_outcome(0, 0.0, 0.0, 1.0), _outcome(1, 0.5, 0.0, 1.0), _outcome(2, 0.0, 0.5, 1.0)]
    counts = plot_heatmap(far_apart, tmp_path / "heat.png", "3 samples", 0.05)
    assert counts["run"] == 3 and counts["not_run"] == 11 * 11 - 3


def test_sample_evaluation_figures_use_the_cell_given(tmp_path):
    rows = [EvaluationRow(id=str(k), label=f"{i},{j}", ok=True, truth_m=[i * 0.1, j * 0.1, 0.0],
                          position_m=[i * 0.1 + 0.001, j * 0.1, 0.0], error_2d_mm=1.0)
            for k, (i, j) in enumerate([(0, 0), (2, 1), (-1, 3)])]
    report = Evaluation(map="m", samples=3, with_truth=3, fixes=3, coverage=1.0, rows=rows)
    paths = plot_sample_evaluation(report, tmp_path, 0.1)
    assert [p.name for p in paths] == ["samples_scatter.png", "samples_heatmap.png"]
    assert all(_decodes(p)[0] > 400 for p in paths)


def test_scatter_draws_errors_with_a_reference_arrow_and_no_fix(tmp_path):
    outcomes = [_outcome(k, x, y, None if k == 3 else 0.3 + 0.1 * k) for k, (x, y) in enumerate(_grid(4))]
    plot_scatter(outcomes, tmp_path / "scatter.png", "tiny")
    assert _decodes(tmp_path / "scatter.png")[0] > 1000
    assert nice_length(0.83) == 0.5 and nice_length(2.4) == 2.0 and nice_length(7.0) == 5.0


def test_sweep_and_fidelity_plots_decode(tmp_path):
    rows = [{"tilt_deg": t, "summary": {"mean_mm": 0.2 + t / 100, "max_mm": 0.9, "coverage_pct": 100.0}}
            for t in (0.0, 5.0)]
    plot_sweep(rows, "tilt_deg", tmp_path / "sweep.png", "tilt", "tilt (deg)")
    plot_fidelity([{"distance_m": d, "overexposure": 4.0, "ratio": 1.004} for d in (1.0, 2.0)], tmp_path / "f.png")
    assert _decodes(tmp_path / "sweep.png") and _decodes(tmp_path / "f.png")


@pytest.mark.parametrize("recorded, plot, name", [
    ("vlc-0.6m-2026-11-25.json", lambda r, p: plot_vlc(r["vlc"], p, "vlc"), "vlc.png"),
    ("vlc-cut-2026-11-27.json", lambda r, p: plot_cut(r["vlc_cut"], p), "cut.png"),
    ("partial-quarter-2026-11-27.json", plot_partial, "partial.png"),
])
def test_recorded_reports_replot(tmp_path, recorded, plot, name):
    plot(json.loads((RESULTS / recorded).read_text()), tmp_path / name)
    assert _decodes(tmp_path / name)[0] > 500


def test_office_walk_plot_decodes(tmp_path):
    records = [{"truth_m": [x, -1.8, 0.0], "ok": x < 0.5, "beacon_id": 17, "fix_m": [x, -1.8, 0.0],
                "filtered_m": [x, -1.8, 0.0]} for x in (-1.0, 0.0, 1.0)]
    report = {"config": {"walk": "zigzag"}, "records": records,
              "summary": {"fixes": {"mean_mm": 1.0}, "coverage_pct": 66.7, "id_errors": 0}}
    plot_walk(report, tmp_path / "office.png")
    assert _decodes(tmp_path / "office.png")[0] > 500


def test_commands_write_figures_into_the_folder_given_and_say_so(tmp_path, capsys):
    assert main(["bench", "tilt", "--tilts", "0", "--scale", "0.1", "--workers", "1",
                 "--figures", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert f"figure {tmp_path / 'tilt-sweep.png'}" in out and (tmp_path / "report.json").exists()
    assert _decodes(tmp_path / "tilt-sweep.png")
    assert main(["bench", "tilt", "--tilts", "0", "--scale", "0.1", "--workers", "1", "--json"]) == 0
    assert "figures" not in json.loads(capsys.readouterr().out)  # no figures unless asked
