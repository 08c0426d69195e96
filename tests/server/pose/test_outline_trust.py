"""The outline fit's trust checks in order: a fit that does not pin the position down is `pose_uncertain`
whatever other minima the optimiser stopped at; `pose_ambiguous` is for two answers each precise enough.

The real case (docs/performance.md, issue 30): slam-ch11_data_7.jpg, a room photo of no panel, against the
600 mm square's map. Its outline fixes the position only to ~300 m; at 4d9cfdf the held-growth probe ended
at a second minimum 1.33 m away that the best fit's covariance did not explain (refused `pose_ambiguous`),
since the analytic Jacobian (1d25d6e) it ends elsewhere (refused `pose_uncertain`): the optimiser's last
digits chose the reason.
"""

from dataclasses import replace

import numpy as np
import pytest

import server.pose.outline as outline
from server.camera import resolve_profile_args
from server.ingest import read_photo_file
from server.locator import locate
from server.outcomes import Refusal
from shared_schemas import FailureReason
from simulator.bench_negatives import PHOTOS, PROFILE, bench_maps

# the minimum the growth-held-low probe's refit ended at on 4d9cfdf (yaw, pitch, roll rad; position m;
# growth px and its gradient): 1330 mm from the best fit, chi-square 9 against its 2
MINIMUM_AT_4D9CFDF = np.array([0.4007490978024986, 0.07598991204108958, 0.7810169377209581, 0.4158620518450876,
                               2.8911242152950467, -1.1681976674381331, 105.59064322225947, -0.3647728871503845,
                               -0.25664682426027413])  # fmt: skip


@pytest.fixture(scope="module")
def finish_arguments(tmp_path_factory):
    """`_finish`'s arguments as `locate` passes them for the photo against the 600 mm square (1 m asked)."""
    profiles, profile = resolve_profile_args([PROFILE])
    frame = read_photo_file(PHOTOS / "slam-ch11_data_7.jpg", profiles, None, profile)[0]
    asked = bench_maps()["square-600"].model_copy(update={"required_sigma_m": 1.0})
    seen: list = []
    finish = outline._finish

    def recording(*args, **kwargs):
        seen.append((args, kwargs))
        return finish(*args, **kwargs)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(outline, "_finish", recording)
        result = locate(frame, asked)
    assert not result.ok and result.reason is FailureReason.pose_uncertain, result.message
    assert len(seen) == 1
    return seen[0]


def test_an_outline_that_fixes_nothing_is_uncertain_whichever_minimum_the_fit_also_found(finish_arguments):
    (problem, best, sigma, probes, minima, *rest), kwargs = finish_arguments
    for others in (minima, [*minima, MINIMUM_AT_4D9CFDF]):
        refusal = outline._finish(problem, best, sigma, probes, others, *rest, **kwargs)
        assert isinstance(refusal, Refusal) and refusal.reason is FailureReason.pose_uncertain, refusal
        assert "fixes the position only to" in refusal.message


def test_the_same_second_minimum_is_ambiguous_where_the_fit_would_be_precise_enough(finish_arguments):
    # the map asking only for what this outline gives: the second answer 1.33 m away is the reason now
    (problem, best, sigma, probes, minima, rule, as_expected, rules), kwargs = finish_arguments
    loose = replace(rules, max_sigma_m=1e6)
    refusal = outline._finish(problem, best, sigma, probes, [*minima, MINIMUM_AT_4D9CFDF], rule, as_expected, loose)
    assert isinstance(refusal, Refusal) and refusal.reason is FailureReason.pose_ambiguous, refusal
    assert "two poses 1330 mm apart" in refusal.message
