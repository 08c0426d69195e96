"""`lumipose bench survey-bearing`: the survey's bearing against the sigma it reports, seed by seed."""

from __future__ import annotations

import json

from lumipose_cli.main import main
from server.survey.rules import SurveyRules


def test_the_bearing_bench_prints_each_surveys_error_over_its_sigma(capsys):
    assert main(["bench", "survey-bearing", "--seeds", "1", "--frames", "12", "--seed", "2", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)["survey_bearing"]
    (run,) = report["runs"]
    assert run["seed"] == 2 and run["frames_used"] >= 10
    # never below the shared compass bias, however many frames (docs/survey.md, the bearing's sigma)
    assert run["sigma_deg"] >= SurveyRules().compass_bias_sigma_deg
    assert run["error_over_sigma"] == run["error_deg"] / run["sigma_deg"] and abs(run["error_deg"]) < 30
    assert set(report["within_sigma_pct"]) == {"1", "2", "3"}
    assert report["compass"] == {"true_bearing_deg": 30.0, "compass_bias_sigma_deg": 10.0,
                                 "compass_noise_sigma_deg": 10.0}
