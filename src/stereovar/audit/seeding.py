"""The audit's seeding check: do the two views share their random streams?

The per-seed residuals of the left and right renders (:func:`stereovar.jobs.audit.seeding_job`)
correlate across views at zero disparity when both views draw the same random numbers (the
same sampler seed); independent seeds give 0. :func:`seeding_summary` combines the frames'
residual correlation at one alignment, :func:`seeding_finding` says in one sentence whether
the streams are shared, and :func:`seeding_rows` gives the verdict table's rows.
"""

from __future__ import annotations

from ..statistics.across import combined_correlation_interval
from ..statistics.residuals import SHARED_STREAMS
from .verdict import _f, _interval, _ok, _row


def seeding_summary(rows: list[dict], alignment: str, region: str = "all") -> tuple:
    """Mean over frames of the residual correlation at one alignment (``zero`` or
    ``ground_truth``; :func:`stereovar.jobs.audit.seeding_job` rows), with the frames'
    block-bootstrap intervals combined on Fisher's :math:`z`
    (:func:`~stereovar.statistics.across.combined_correlation_interval`)."""
    chosen = [r for r in rows if r["alignment"] == alignment and r["region"] == region]
    return combined_correlation_interval(
        [_f(r["rho"]) for r in chosen], [_f(r["low"]) for r in chosen],
        [_f(r["high"]) for r in chosen],
    )


def seeding_finding(rows: list[dict]) -> dict:
    """Do the two views share their random streams? From the residual correlation at zero
    disparity (:func:`seeding_summary`) against
    :data:`~stereovar.statistics.residuals.SHARED_STREAMS`.

    Returns
    -------
    dict
        ``shared`` (True, False, or None when undefined), ``zero`` and ``ground_truth``
        (value, low, high) and ``text``, one plain-language sentence.

    Examples
    --------
    >>> rows = [{"alignment": "zero", "region": "all", "rho": 0.3, "low": 0.2, "high": 0.4},
    ...         {"alignment": "ground_truth", "region": "all", "rho": 0.1, "low": 0.0,
    ...          "high": 0.2}]
    >>> seeding_finding(rows)["shared"]
    True
    """
    zero = seeding_summary(rows, "zero")
    gt = seeding_summary(rows, "ground_truth")

    def iv(t):
        return _interval(*t)

    if not _ok(zero[0], zero[1]):
        shared, text = None, (
            "Whether the two views share their random streams cannot be told on these frames "
            f"(residual correlation at zero disparity {iv(zero)})."
        )
    elif zero[1] > SHARED_STREAMS:
        shared, text = True, (
            "The two views share their random streams: the per-seed noise of the left and "
            f"right renders correlates at zero disparity, {iv(zero)} (at the ground-truth "
            f"disparity {iv(gt)}), where independent seeds give 0. This is what the same "
            "sampler seed in both views does (Cycles seed 0, the default of Kubric, "
            "BlenderProc and Infinigen); a network can match the noise itself."
        )
    else:
        shared, text = False, (
            "The two views' random streams are independent: the per-seed noise does not "
            f"correlate across views at zero disparity, {iv(zero)} (at the ground-truth "
            f"disparity {iv(gt)})."
        )
    return {"shared": shared, "zero": zero, "ground_truth": gt, "text": text}


def seeding_rows(rows: list[dict]) -> list[dict]:
    """:data:`~stereovar.audit.verdict.VERDICT_COLUMNS` rows of the residual correlation over
    frames, per region."""
    out = []
    for region in ("all", "non_glass", "glass"):
        for alignment, label in (
            ("zero", "residual rho at zero disparity"),
            ("ground_truth", "residual rho at the ground-truth disparity"),
        ):
            value, low, high = seeding_summary(rows, alignment, region)
            if region != "all" and not _ok(value):
                continue
            note = "shared random streams" if alignment == "zero" else "seeding"
            out.append(_row(label, region, value, low, high, note))
    return out
