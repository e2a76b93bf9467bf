"""The converged reference a mitigation's images are graded against: a moment store's pooled
mean, or the source's untransformed renders split in half, each half's images remade from
that half's renders alone when a transform read the seed statistics."""

from __future__ import annotations

import numpy as np

from ..errors import StereovarError
from .common import view_stack
from .transform import seed_moments


def reference_moments(path) -> tuple[np.ndarray, np.ndarray]:
    """A converged reference from one view's moment store: the pooled mean of both half
    renders and the variance of that mean, per channel.

    .. math::

        R_c = m_{1,c}, \\qquad V_c = \\frac{S_c^2}{n}

    with :math:`m_{1,c}` the mean of the :math:`n` finite samples and :math:`S_c^2` their
    unbiased variance (:func:`stereovar.estimators.moments.sample_variance`); NaN where a
    pixel has fewer than two finite samples.
    """
    from ..estimators.moments import pooled_sample_moments, sample_variance
    from ..io.store import load_store

    ds = load_store(path, "moment store", ["sample_mean", "sample_mean_sq", "n_samples"])
    order = ("half", "y", "x", "channel")
    m1, m2, n = pooled_sample_moments(
        ds["sample_mean"].transpose(*order).values,
        ds["sample_mean_sq"].transpose(*order).values,
        ds["n_samples"].transpose("half", "y", "x").values,
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        var = sample_variance(m1, m2, n) / n[..., None]
    ok = (n >= 2)[..., None]
    return np.where(ok, m1, np.nan), np.where(ok, var, np.nan)


def _reference(spec, loaded: dict, *, images, seeds, attrs: dict, paths, view: str):
    """``quality(mask)`` of one view's images (sorted by seed index ``seeds``) against its
    reference: a moment store's path (:func:`reference_moments`,
    :func:`stereovar.statistics.utility.image_quality`), or a list of the source's
    untransformed render stores, split in half (:func:`split_half_images`,
    :func:`stereovar.statistics.utility.split_half_quality`). ``loaded`` maps a tuple of
    render-store paths already read to ``(stack, seeds)``: the untransformed row grades its own
    renders, which are not read again."""
    from ..statistics.utility import RESULT_KEYS, image_quality, split_half_quality
    from ..transforms import get_transform

    if isinstance(spec, (list, tuple)):
        key = tuple(str(p) for p in spec)
        if key not in loaded:
            loaded[key] = view_stack(spec)[:2]
        raw, raw_seeds = loaded[key]
        order = np.argsort(raw_seeds, kind="stable")
        raw, raw_seeds = raw[order], np.asarray(raw_seeds)[order]
        if not np.array_equal(raw_seeds, seeds):
            raise StereovarError(
                f"{view} view: the images have seed indices {seeds.tolist()} and the source's "
                f"renders {raw_seeds.tolist()}; split-half grading needs the same seeds"
            )
        halves = split_halves(len(seeds))
        name = attrs.get("transform")
        if name and "seed_var" in get_transform(name).reads and len(halves[0]) < 2:
            reason = (
                f"split-half grading of {name} needs at least 2 seeds per half "
                f"(N >= 4, got {len(seeds)})"
            )
            return lambda mask: {
                **dict.fromkeys(RESULT_KEYS, np.nan),
                "n_pixels": 0,
                "n_images": len(seeds),
                "reason": reason,
            }
        made = split_half_images(images, raw, seeds, halves, attrs=attrs, paths=paths, view=view)
        raw_halves = tuple(raw[h] for h in halves)
        return lambda mask: split_half_quality(images, made, raw_halves, mask=mask)
    mean, var = reference_moments(spec)
    return lambda mask: image_quality(images, mean, reference_var=var, mask=mask)


def split_halves(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Positions of the two halves of :math:`n` seeds sorted by seed index: the first
    :math:`\\lfloor n/2 \\rfloor` and the rest.

    Examples
    --------
    >>> [h.tolist() for h in split_halves(5)]
    [[0, 1], [2, 3, 4]]
    """
    if n < 2:
        raise StereovarError(f"split-half grading needs at least 2 seeds per view, got {n}")
    return np.arange(n // 2), np.arange(n // 2, n)


MEAN_READS = frozenset({"seed_mean", "seed_var", "n_seeds"})
"""The :class:`~stereovar.transforms.base.TransformInputs` fields computed over a view's
seeds: a transform that reads one is remade from each half for split-half grading."""


def split_half_images(images, raw, seeds, halves, *, attrs: dict, paths, view: str) -> tuple:
    """The images of each half of the seeds made from that half's renders alone.

    An image that reads its own render only (no transform, a render-time policy, ``denoise``,
    ``denoise_sensor``) is the shipped one. A transform that reads the seed statistics
    (:data:`MEAN_READS`: ``equalise``, ``sensor_only``) read them over all :math:`N` seeds, so
    its shipped images share every render's noise; it is applied again to each half's renders
    with that half's seed mean, variance and count
    (:func:`~stereovar.jobs.transform.seed_moments`), its options from the store
    (``transform_options``) and each seed's recorded draw seed (``transform_seed``), as
    :func:`~stereovar.jobs.transform.transform_job` applies it. What this grading can and
    cannot take out is in :func:`stereovar.statistics.utility.split_half_quality`.

    Parameters
    ----------
    images : numpy.ndarray, shape (N, H, W, 3)
        The shipped images, sorted by seed index.
    raw : numpy.ndarray, shape (N, H, W, 3)
        The source's renders of the same seeds, in the same order.
    seeds : numpy.ndarray of int (N,)
        Their seed indices.
    halves : pair of numpy.ndarray of int
        Positions of each half (:func:`split_halves`).
    attrs : dict, keyword-only
        The images' store attributes (``transform``, ``transform_options``).
    paths : list, keyword-only
        The images' render stores (read again for ``transform_seed`` only when remade).
    view : str, keyword-only

    Returns
    -------
    tuple of numpy.ndarray
        One (M, H, W, 3) stack per half.
    """
    import ast

    from ..transforms import TransformInputs, check_reads, get_transform

    name = attrs.get("transform")
    t = get_transform(name) if name else None
    if t is None or not MEAN_READS & {*t.reads, *t.optional_reads}:
        return tuple(images[h] for h in halves)
    available = {*MEAN_READS, "render", "view", "seed_index", "rng_seed"}
    check_reads(t, available, source=f"split-half grading of {view} {name} images")
    options = dict(ast.literal_eval(attrs.get("transform_options") or "[]"))
    draws = _transform_seeds(paths)
    made = []
    for h in halves:
        mean, var = seed_moments(raw[h])
        made.append(
            np.stack(
                [
                    t(
                        TransformInputs(
                            render=raw[k].astype(np.float32),
                            view=view,
                            seed_index=int(seeds[k]),
                            rng_seed=draws[int(seeds[k])],
                            seed_mean=mean,
                            seed_var=var,
                            n_seeds=len(h),
                        ),
                        **options,
                    )
                    for k in h
                ]
            )
        )
    return tuple(made)


def _transform_seeds(paths) -> dict[int, int]:
    """Each seed index's recorded ``transform_seed`` in transformed render stores."""
    from ..io.store import load_store

    out = {}
    for path in paths:
        ds = load_store(path, "render store", ["radiance"])
        out.update(
            zip(
                (int(s) for s in ds["seed"].values),
                (int(s) for s in ds["transform_seed"].values),
                strict=True,
            )
        )
    return out
