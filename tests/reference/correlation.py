"""One scene's correlation rows straight from the variance fields (Eq. 2 then Eq. 3).

The workflow splits this into the warp job (which stores the alignment) and the correlation
job (which reads it back); the tests call the composition.
"""

from __future__ import annotations

from stereovar.statistics.rows import correlation_rows as rows_from_alignment
from stereovar.statistics.warp import align_variance


def correlation_rows(
    sigma_left,
    sigma_right,
    ground_truth_left,
    *,
    sign: int,
    finite_left=None,
    finite_right=None,
    min_pixels: int = 30,
) -> list[dict]:
    """Rows region x statistic of one scene (:func:`stereovar.statistics.rows.correlation_rows`)."""
    aligned = align_variance(
        sigma_left,
        sigma_right,
        ground_truth_left,
        sign=sign,
        finite_left=finite_left,
        finite_right=finite_right,
    )
    return rows_from_alignment(
        sigma_left,
        sigma_right,
        aligned,
        ground_truth_left["glass"],
        finite_right=finite_right,
        min_pixels=min_pixels,
    )
