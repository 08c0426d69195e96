"""The paper's Table 2 from recorded samples: 2D error against each sample's truth, and coverage."""

from __future__ import annotations

import numpy as np

from shared_schemas import LocateResult
from shared_schemas.api import Evaluation, EvaluationRow, SampleInfo, cell_truth_m


def sample_truth_m(sample: SampleInfo, cell_m: float, height_m: float) -> list[float] | None:
    """Ground truth of the frame if it has one, else the position of its grid-cell label."""
    if sample.meta.ground_truth is not None:
        return list(sample.meta.ground_truth.position_m)
    return cell_truth_m(sample.label, cell_m, height_m)


def evaluate(
    map_name: str, located: list[tuple[SampleInfo, LocateResult | str]], cell_m: float, height_m: float = 0.0
) -> Evaluation:
    """Error statistics (mm, horizontal) over the samples that have a truth; coverage over all.

    A sample's result is a LocateResult, or the error code that refused its frame now (a stored
    profile its camera names was deleted or damaged since): a row without a fix."""
    rows = []
    for sample, result in located:
        truth = sample_truth_m(sample, cell_m, height_m)
        if isinstance(result, str):
            rows.append(EvaluationRow(id=sample.id, label=sample.label, ok=False, reason=result, truth_m=truth))
            continue
        error = None
        if result.ok and result.position_m is not None and truth is not None:
            error = 1000.0 * float(np.hypot(result.position_m[0] - truth[0], result.position_m[1] - truth[1]))
        rows.append(
            EvaluationRow(
                id=sample.id,
                label=sample.label,
                ok=result.ok,
                reason=result.reason.value if result.reason else None,
                truth_m=truth,
                position_m=result.position_m,
                error_2d_mm=error,
            )
        )
    errors = np.array([row.error_2d_mm for row in rows if row.error_2d_mm is not None])
    stats = {}
    if errors.size:
        stats = {
            "mean_mm": float(errors.mean()),
            "std_mm": float(errors.std()),
            "min_mm": float(errors.min()),
            "max_mm": float(errors.max()),
        }
    fixes = sum(row.ok for row in rows)
    return Evaluation(
        map=map_name,
        samples=len(rows),
        with_truth=sum(row.truth_m is not None for row in rows),
        fixes=fixes,
        coverage=fixes / len(rows) if rows else 0.0,
        rows=rows,
        **stats,
    )
