"""The user's network's table and reading: accuracy and EPE of every input beside the best
constant's, the drops under each shuffle with tile-bootstrap intervals, and one sentence.

The scored rows of every frame (:func:`stereovar.probe.user_model.score_frame`) are summed per
input and tile; the intervals come from a tile bootstrap stratified by frame (each replicate
draws every frame's own tiles with replacement), every input paired by tile
(:func:`model_rows`). The reading (:func:`model_reading`) says whether the network uses the
Monte Carlo cue, and says *not testable* instead of *no use* where the checks of
:mod:`stereovar.probe.user_checks` fail: a network whose output does not respond to its input,
or that is no better than a constant disparity, would read *no use* whatever it is.

Importing this module imports PyTorch (through :mod:`stereovar.probe.user_model`'s constants).
"""

from __future__ import annotations

import math

import numpy as np

from ..statistics.bootstrap import draw_counts, percentile_interval
from .user_checks import CONSTANT_ROW
from .user_model import COMPARISONS, MODEL_INPUTS, MODEL_SUMS

__all__ = [
    "SCORED",
    "model_lines",
    "model_reading",
    "model_rows",
    "nonfinite_warning",
]

SCORED = (*MODEL_INPUTS, CONSTANT_ROW)
"""The rows scored against the ground truth: the model's inputs and the best constant."""


def _sums_matrix(rows) -> tuple[np.ndarray, list]:
    """(scored row, tile, sum) array over the (scene, tile) keys of ``rows`` of a
    :data:`SCORED` kind (zeros where one scored no pixel of a tile) and the scene of each
    tile."""
    rows = [r for r in rows if r["test_input"] in SCORED]
    keys = sorted({(r["scene"], int(r["tile"])) for r in rows})
    index = {k: i for i, k in enumerate(keys)}
    out = np.zeros((len(SCORED), len(keys), len(MODEL_SUMS)))
    for r in rows:
        i = SCORED.index(r["test_input"])
        out[i, index[(r["scene"], int(r["tile"]))]] += [float(r.get(s, 0)) for s in MODEL_SUMS]
    return out, [k[0] for k in keys]


def _stratified_counts(scenes, reps: int, seed) -> np.ndarray:
    """Bootstrap draw counts (reps, tiles): each scene's tiles drawn with replacement among
    themselves (:func:`stereovar.statistics.bootstrap.draw_counts` per scene)."""
    scenes = np.asarray(scenes, dtype=object)
    counts = np.zeros((int(reps), scenes.size))
    for j, scene in enumerate(dict.fromkeys(scenes.tolist())):
        cols = np.flatnonzero(scenes == scene)
        counts[:, cols] = draw_counts(cols.size, int(reps), [int(seed), j])
    return counts


def _metrics(sums) -> dict:
    """Accuracy and EPE of each scored row from summed (..., row, sum) arrays."""
    n = sums[..., 0]
    with np.errstate(invalid="ignore", divide="ignore"):
        acc = np.where(n > 0, sums[..., 1] / n, np.nan)
        epe = np.where(n > 0, sums[..., 2] / n, np.nan)
    return {"accuracy": acc, "epe": epe}


def model_rows(rows, *, reps: int = 1000, seed: int = 0, level: float = 0.95) -> list[dict]:
    """The user model's table: accuracy and EPE per input and of the best constant, the drops
    under each shuffle and the gain over the constant.

    Rows ``normal``, ``shuffled``, ``camera``, ``camera_shuffled`` and ``constant`` (the best
    constant answers of each frame, :mod:`stereovar.probe.user_checks`, scored on the same
    pixels) give

    .. math:: A = \\frac{\\sum_t \\mathrm{hits}_t}{\\sum_t n_t}, \\qquad
        \\mathrm{EPE} = \\frac{\\sum_t |\\hat d - d|_t}{\\sum_t n_t};

    rows ``mc_shuffle`` and ``camera_shuffle`` the drop of accuracy and the rise of EPE
    under each shuffle (:data:`~stereovar.probe.user_model.COMPARISONS`: before minus after,
    after minus before), row ``mc_minus_camera`` the difference of the two, and row
    ``over_constant`` the network's gain over the constant on the renders, the same
    differences of ``normal`` and ``constant``:

    .. math:: G_A = A(\\text{normal}) - A(\\text{constant}), \\qquad
        G_E = \\mathrm{EPE}(\\text{constant}) - \\mathrm{EPE}(\\text{normal}).

    Each with a percentile interval of a tile bootstrap stratified by frame (``*_low``,
    ``*_high``); the rows are paired by tile in every replicate. A NaN or Inf prediction is
    one of the :math:`n_t` pixels, a miss, and adds
    :func:`~stereovar.probe.user_model.nonfinite_bound` to the EPE's sum;
    ``nonfinite_share`` is their share of the scored pixels of a row (its rise under a
    comparison, after minus before; the difference of the two rises for
    ``mc_minus_camera``).

    Parameters
    ----------
    rows : list of dict
        :func:`~stereovar.probe.user_model.score_frame`'s rows of every frame (rows of
        another ``test_input``, such as the response sums, are left out).
    reps, seed, level : keyword-only

    Returns
    -------
    list of dict
        ``row``, ``accuracy``, ``accuracy_low``, ``accuracy_high``, ``epe``, ``epe_low``,
        ``epe_high``, ``nonfinite_share``, ``n_pixels``, ``n_tiles``, ``frames``.
    """
    sums, scenes = _sums_matrix(list(rows))
    if not scenes:
        raise ValueError("no scored pixel: the frames have no valid ground truth")
    counts = _stratified_counts(scenes, reps, seed)
    total = sums.sum(axis=1)  # (row, sum)
    point = _metrics(total)
    nonfinite = total[:, MODEL_SUMS.index("nonfinite")]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(total[:, 0] > 0, nonfinite / total[:, 0], np.nan)  # (row,)
    boot = _metrics(np.einsum("rt,its->ris", counts, sums))  # (reps, row)

    def drop(values, before, after):
        return values[..., SCORED.index(before)] - values[..., SCORED.index(after)]

    def summary(acc_p, acc_b, epe_p, epe_b) -> dict:
        lo_a, hi_a = percentile_interval(acc_b, level)
        lo_e, hi_e = percentile_interval(epe_b, level)
        return {
            "accuracy": float(acc_p),
            "accuracy_low": lo_a,
            "accuracy_high": hi_a,
            "epe": float(epe_p),
            "epe_low": lo_e,
            "epe_high": hi_e,
        }

    def compare(before, after) -> tuple:
        return (
            drop(point["accuracy"], before, after),
            drop(boot["accuracy"], before, after),
            -drop(point["epe"], before, after),
            -drop(boot["epe"], before, after),
        )

    common = {"n_tiles": len(scenes), "frames": len(set(scenes))}
    out = []
    for i, kind in enumerate(SCORED):
        out.append(
            {
                "row": kind,
                **summary(
                    point["accuracy"][i], boot["accuracy"][:, i], point["epe"][i], boot["epe"][:, i]
                ),
                "nonfinite_share": float(share[i]),
                "n_pixels": int(sums[i, :, 0].sum()),
                **common,
            }
        )
    diffs, rises = {}, {}
    for name, (before, after) in COMPARISONS.items():
        diffs[name] = compare(before, after)
        rises[name] = -drop(share, before, after)
    mc, cam = diffs["mc_shuffle"], diffs["camera_shuffle"]
    diffs["mc_minus_camera"] = tuple(a - b for a, b in zip(mc, cam, strict=True))
    rises["mc_minus_camera"] = rises["mc_shuffle"] - rises["camera_shuffle"]
    diffs["over_constant"] = compare("normal", CONSTANT_ROW)
    rises["over_constant"] = -drop(share, "normal", CONSTANT_ROW)
    for name, values in diffs.items():
        out.append(
            {
                "row": name,
                **summary(*values),
                "nonfinite_share": float(rises[name]),
                "n_pixels": int(sums[0, :, 0].sum()),
                **common,
            }
        )
    return out


def _points(value, low, high, scale=100.0) -> str:
    return f"{scale * value:+.2f} [{scale * low:+.2f}, {scale * high:+.2f}]"


def _share(value: float) -> str:
    """A share in percent, one decimal; a share that rounds to 0 or 100 % but is not says
    so.

    Examples
    --------
    >>> _share(0.5), _share(0.0), _share(2e-5), _share(1.0)
    ('50.0 %', '0 %', '< 0.1 %', '100 %')
    """
    if value <= 0 or value >= 1:
        return f"{100 * value:.0f} %"
    if value < 0.0005:
        return "< 0.1 %"
    if value > 0.9995:
        return "> 99.9 %"
    return f"{100 * value:.1f} %"


def nonfinite_warning(rows) -> str | None:
    """The one-line warning when the model returned NaN or Inf at any scored pixel, with the
    share of each input (:func:`model_rows`' ``nonfinite_share``); None when it never did.

    Examples
    --------
    >>> rows = [{"row": k, "nonfinite_share": s} for k, s in zip(MODEL_INPUTS, (0, 0.5, 0, 0))]
    >>> nonfinite_warning(rows)[:85]
    'the model returned NaN or Inf disparity at scored pixels (normal 0 %, shuffled 50.0 %'
    >>> nonfinite_warning(rows[:1]) is None
    True
    """
    shares = {r["row"]: r["nonfinite_share"] for r in rows if r["row"] in MODEL_INPUTS}
    if not any(s > 0 for s in shares.values()):
        return None
    listed = ", ".join(f"{kind} {_share(s)}" for kind, s in shares.items())
    return (
        f"the model returned NaN or Inf disparity at scored pixels ({listed}); they "
        "count as misses at an end-point error of the frame's largest disparity (column "
        "nonfinite_share); check the model for a division by zero or a log of a negative "
        "number"
    )


def model_lines(rows) -> list[str]:
    """The accuracy and EPE of the network on every input beside the best constant's (the
    same for every input: one ground truth, the same pixels), as lines of text.

    Examples
    --------
    >>> rows = [{"row": k, "accuracy": a, "epe": e} for k, a, e in
    ...         (("normal", 0.9, 0.25), ("shuffled", 0.85, 0.3), ("constant", 0.5, 1.0))]
    >>> print("\\n".join(model_lines(rows)))
    input             accuracy   EPE px    best constant: accuracy   EPE px
    normal              90.0 %    0.250                      50.0 %    1.000
    shuffled            85.0 %    0.300                      50.0 %    1.000
    """
    by = {r["row"]: r for r in rows}
    c = by[CONSTANT_ROW]
    constant = f"{100 * c['accuracy']:22.1f} % {c['epe']:8.3f}"
    lines = [f"{'input':<16} {'accuracy':>9} {'EPE px':>8}    best constant: accuracy   EPE px"]
    for kind in MODEL_INPUTS:
        if kind in by:
            r = by[kind]
            lines.append(
                f"{kind:<16} {100 * r['accuracy']:7.1f} % {r['epe']:8.3f}   {constant}"
            )
    return lines


def model_reading(rows, checks: dict | None = None) -> str:
    """One sentence: does the model use the Monte Carlo cue, from :func:`model_rows`.

    It does when the accuracy drop under the Monte Carlo shuffle is above 0 and above the
    camera shuffle's (the interval of ``mc_minus_camera`` lies above 0); the shuffle helps it
    when that interval lies below 0; and it shows no use when the interval holds 0, unless
    ``checks`` (:func:`stereovar.probe.user_checks.testability`) found that the network does
    not respond to its input or is no better than a constant disparity: then it is *not
    testable*, since an untrained or broken network reads *no use* whatever it is. The
    sentence gives the network's accuracy and EPE on the renders beside the best constant's.
    """
    by = {r["row"]: r for r in rows}
    mc, cam, diff = by["mc_shuffle"], by["camera_shuffle"], by["mc_minus_camera"]
    numbers = (
        f"accuracy drop under the Monte Carlo shuffle "
        f"{_points(mc['accuracy'], mc['accuracy_low'], mc['accuracy_high'])} points, under the "
        "camera-noise shuffle "
        f"{_points(cam['accuracy'], cam['accuracy_low'], cam['accuracy_high'])}"
        f", difference {_points(diff['accuracy'], diff['accuracy_low'], diff['accuracy_high'])}"
        f" (EPE rise {mc['epe']:+.3f} vs {cam['epe']:+.3f} px)"
    )
    if CONSTANT_ROW in by:
        normal, constant = by["normal"], by[CONSTANT_ROW]
        numbers += (
            f"; on the renders accuracy {100 * normal['accuracy']:.1f} % and EPE "
            f"{normal['epe']:.3f} px, the best constant's {100 * constant['accuracy']:.1f} % "
            f"and {constant['epe']:.3f} px"
        )
    low, high = diff["accuracy_low"], diff["accuracy_high"]
    testable = checks is None or checks["testable"]
    if math.isfinite(low) and low > 0:
        verdict = "the model uses the Monte Carlo cue"
    elif math.isfinite(high) and high < 0:
        verdict = "the shuffle helps the model more than camera noise's (not a cue use)"
    elif not testable:
        verdict = (
            f"not testable: {checks['problem']}; an untrained or broken checkpoint would "
            "read no use the same way"
        )
    elif not (math.isfinite(low) and math.isfinite(high)):
        verdict = "not determined (too few tiles for an interval)"
    else:
        verdict = "no use of the Monte Carlo cue detected"
    return f"{verdict}: {numbers}, over {diff['frames']} frames ({diff['n_tiles']} tiles)."
