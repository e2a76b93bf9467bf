"""Jobs of ``workflow/rules/mitigations.smk``: auxiliary passes, store transforms, each
scene's mitigation measurements, and the mitigation table and figure."""

from __future__ import annotations

import time

import numpy as np

from ..errors import StereovarError
from .common import log, view_stack


def aux_job(spec, out, *, view, spp, renderer="mitsuba", variant="auto", threads=None, **rig):
    """Render one view's auxiliary passes (albedo and shading normal) for the denoiser into
    ``out`` (:func:`stereovar.layout.aux_store`), with the sampler seed of seed index
    ``"aux"`` (:func:`stereovar.seeding.render_seed`), never one of the renders'."""
    import xarray as xr

    from ..io.renders import CHANNELS, pixel_coords
    from ..io.store import write_dataset
    from ..seeding import render_seed
    from .common import prepare_scene

    prepared = prepare_scene(spec, renderer=renderer, variant=variant, threads=threads, **rig)
    name = prepared.spec["name"]
    seed = render_seed(name, view, int(spp), "aux")
    start = time.perf_counter()
    albedo, normal = prepared.render_aux(view, spp=int(spp), seed=seed)
    elapsed = time.perf_counter() - start
    dims = ("y", "x", "channel")
    ds = xr.Dataset(
        {
            "albedo": (dims, np.asarray(albedo, np.float32), {"long_name": "first-hit albedo"}),
            "normal": (
                dims,
                np.asarray(normal, np.float32),
                {"long_name": "first-hit shading normal (world space)"},
            ),
        },
        coords={
            **pixel_coords(albedo.shape[0], albedo.shape[1]),
            "channel": ("channel", list(CHANNELS)),
            "view": ((), view),
        },
        attrs={
            **prepared.provenance,
            "spp": int(spp),
            "sampler_seed": int(seed),
            "render_seconds": float(elapsed),
        },
    )
    write_dataset(ds, out)
    log.info("%s %s: albedo and normal at spp %d in %.2f s", name, view, int(spp), elapsed)


def seed_moments(stack) -> tuple[np.ndarray, np.ndarray]:
    """Per-channel mean and unbiased variance over the seeds of one view's renders, from
    each pixel's finite renders (NaN where fewer than two are finite).

    .. math::

        \\bar I_c = \\frac1{N_f} \\sum_{n} I_{n,c}, \\qquad
        \\hat\\sigma_c^2 = \\frac1{N_f - 1} \\sum_n \\bigl(I_{n,c} - \\bar I_c\\bigr)^2

    over the :math:`N_f` finite renders of the pixel (Eq. 1 per channel, paper Sec. 2.1).

    Examples
    --------
    >>> m, v = seed_moments(np.array([1.0, 3.0]).reshape(2, 1, 1, 1))
    >>> float(m[0, 0, 0]), float(v[0, 0, 0])
    (2.0, 2.0)
    """
    x = np.asarray(stack, dtype=np.float64)
    finite = np.isfinite(x)
    n = finite.sum(axis=0)
    x0 = np.where(finite, x, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = x0.sum(axis=0) / n
        dev = np.where(finite, x - mean, 0.0)
        var = (dev**2).sum(axis=0) / (n - 1)
    mean = np.where(n >= 1, mean, np.nan)
    var = np.where(n >= 2, var, np.nan)
    return mean, var


def transform_job(
    renders,
    out,
    *,
    transform,
    batch,
    view,
    seed=0,
    aux=None,
    options=None,
) -> None:
    """Apply the store transform ``transform`` to the renders of seed indices ``batch`` of
    one view and write them as a render store ``out`` (:mod:`stereovar.io.renders`).

    ``renders`` are every render store of the view (all seeds: the seed mean and variance
    that ``equalise`` and ``sensor_only`` read are over all of them); ``aux`` the view's
    auxiliary-pass store or None. Each render's random draws use the seed
    :math:`\\mathrm{SHA256}(\\text{transform}, \\text{scene}, \\text{view}, \\text{spp},
    n, \\text{seed})`, recorded in the store (``transform_seed``), with the transform's name,
    options and the time it took (``transform_seconds``).
    """
    from ..io.renders import render_dataset
    from ..io.store import load_store, write_dataset
    from ..seeding import derive_seed
    from ..transforms import TransformInputs, check_reads, get_transform

    t = get_transform(transform)
    stack, seeds, samplers, attrs = view_stack(renders)
    wanted = [int(s) for s in batch]
    missing = sorted(set(wanted) - set(seeds.tolist()))
    if missing:
        raise StereovarError(f"transform {transform}: seed indices {missing} not in {renders}")
    mean, var = seed_moments(stack)
    extra = {}
    if aux is not None:
        a = load_store(aux, "auxiliary-pass store", ["albedo", "normal"])
        extra = {
            k: a[k].transpose("y", "x", "channel").values.astype(np.float32)
            for k in ("albedo", "normal")
        }
    fields = {"seed_mean": mean, "seed_var": var, "n_seeds": len(seeds), **extra}
    check_reads(t, {*fields, "render", "view", "seed_index", "rng_seed"}, source=str(out))
    scene, spp = attrs.get("scene", ""), attrs.get("spp", "")
    options = dict(options or {})
    images, rng_seeds, values = [], [], []
    start = time.perf_counter()
    for index in wanted:
        k = int(np.flatnonzero(seeds == index)[0])
        rng_seed = derive_seed("transform", transform, scene, view, spp, index, int(seed))
        inputs = TransformInputs(
            render=stack[k].astype(np.float32),
            view=view,
            seed_index=index,
            rng_seed=rng_seed,
            **fields,
        )
        images.append(t(inputs, **options))
        rng_seeds.append(rng_seed)
        values.append(int(samplers[k]))
    elapsed = time.perf_counter() - start
    height, width = stack.shape[1:3]
    ds = render_dataset(
        images,
        view=view,
        seeds=wanted,
        sampler_seeds=values,
        attrs={
            **attrs,
            "transform": transform,
            "transform_options": repr(sorted(options.items())),
            "transform_aux": ",".join(sorted(extra)) or "none",
            "transform_seconds": float(elapsed),
            "transform_megapixels": float(len(wanted) * height * width / 1e6),
            # an output written as integers says so, as an imported PNG does, so that the
            # intensity control's quantisation term and the matched null read its encoding
            **(
                {"bit_depth": t.encoding["bits"], "transfer": t.encoding["transfer"],
                 "full_scale": t.encoding["scale"], "file_format": "PNG"}
                if t.encoding else {}
            ),
        },
    )
    ds = ds.assign_coords(transform_seed=("seed", np.asarray(rng_seeds, dtype=np.int64)))
    write_dataset(ds, out, chunk_dims={"seed": 1})
    log.info(
        "%s %s spp %s: %s on %d renders in %.2f s (%.1f ms per megapixel)%s",
        scene,
        view,
        spp,
        transform,
        len(wanted),
        elapsed,
        1e3 * elapsed / max(len(wanted) * height * width / 1e6, 1e-12),
        f" with {', '.join(sorted(extra))}" if extra else "",
    )


MITIGATION_SCENE_COLUMNS = [
    "scene",
    "spp",
    "n_seeds",
    "region",
    "quantity",
    "value",
    "low",
    "high",
    "n_pixels",
    "reason",
]
"""Columns of ``results/{source}[/{transform}]/seeds/mitigation/{scene}/spp{spp}.csv``: one
row per region and quantity (:data:`SCENE_QUANTITIES`)."""

RESIDUAL_QUANTITIES = {"ground_truth": "residual_rho_gt", "zero": "residual_rho_zero"}
"""The quantity of each alignment's residual correlation over every disparity; a band's is
``{quantity}_{band}`` (:func:`stereovar.statistics.residuals.band_label`, e.g.
``residual_rho_gt_d0-2``)."""


SCENE_QUANTITIES = (
    "residual_rho_gt",
    "residual_rho_zero",
    # per band of stereovar.statistics.residuals.DISPARITY_BANDS (literal: this module imports
    # no statistics at import time)
    "residual_rho_gt_d0-2",
    "residual_rho_gt_d2-8",
    "residual_rho_gt_d8-inf",
    "residual_rho_zero_d0-2",
    "residual_rho_zero_d2-8",
    "residual_rho_zero_d8-inf",
    "psnr",
    "mse",
    "relative_mse",
    "bias",
    "relative_bias",
    "reference_noise",
    "transform_ms_per_mpix",
)
"""What one scene's mitigation rows measure: the cross-view residual correlation, each pixel
standardised, at the ground-truth alignment and at zero disparity over every disparity (with
block-bootstrap intervals) and per disparity band
(:data:`stereovar.statistics.residuals.DISPARITY_BANDS`), the image quality of the images
against the converged reference (both views pooled), and the store transform's time per
megapixel (NaN for renders that were not transformed)."""


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
    with that half's seed mean, variance and count (:func:`seed_moments`), its options from the
    store (``transform_options``) and each seed's recorded draw seed (``transform_seed``), as
    :func:`transform_job` applies it. What this grading can and cannot take out is in
    :func:`stereovar.statistics.utility.split_half_quality`.

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


def mitigation_scene_job(
    left, right, ground_truth, reference: dict, out, *, analysis=None, controls=None
) -> list[dict]:
    """One scene's mitigation measurements (:data:`MITIGATION_SCENE_COLUMNS`).

    ``left`` and ``right`` are the view's render stores (transformed or not), ``reference``
    maps each view to its converged reference: a moment store
    (:func:`stereovar.statistics.utility.image_quality`), or the source's untransformed render
    stores (an audit's, Cycles'), split in half (:func:`split_half_images`,
    :func:`stereovar.statistics.utility.split_half_quality`). The residual correlation
    (:func:`stereovar.statistics.residuals.residual_correlation`, each pixel standardised) is
    over the left view's regions of the valid set :math:`\\Omega`, over every disparity and
    per band of :data:`~stereovar.statistics.residuals.DISPARITY_BANDS`; the image quality over
    each view's own regions (its ground-truth glass mask), both views pooled by pixel count.
    """
    from ..io.store import load_store
    from ..io.tables import write_tables
    from ..statistics.regions import REGIONS, region_masks, valid_set
    from ..statistics.residuals import ALL_BANDS, DISPARITY_BANDS, residual_correlation
    from .correlation import analysis_settings

    settings, _ = analysis_settings(analysis, controls)
    gt = load_store(ground_truth, "ground-truth store", ["disparity", "valid", "glass"])
    stacks, attrs, seed_order, loaded = {}, {}, {}, {}
    paths_of = {"left": left, "right": right}
    for view, paths in paths_of.items():
        stacks[view], seeds, _, attrs[view] = view_stack(paths)
        loaded[tuple(str(p) for p in paths)] = (stacks[view], seeds)
        order = np.argsort(seeds, kind="stable")
        stacks[view], seed_order[view] = stacks[view][order], seeds[order]
    gl = gt.sel(view="left")
    sign = int(gt.attrs.get("disparity_sign", 1))
    disparity = gl["disparity"].transpose("y", "x").values
    omega = valid_set(disparity, sign=sign, valid=gl["valid"].transpose("y", "x").values)
    masks = region_masks(gl, omega)
    material = gt.attrs.get("material_mask") != "none"
    regions = REGIONS if material else ("all",)
    masks = {r: masks[r] for r in regions}
    scene, spp = attrs["left"].get("scene", ""), int(attrs["left"].get("spp", 0))
    n_seeds = int(stacks["left"].shape[0])
    rows = []

    def add(region, quantity, value, low=np.nan, high=np.nan, n_pixels=0, reason=""):
        rows.append(
            {
                "scene": scene,
                "spp": spp,
                "n_seeds": n_seeds,
                "region": region,
                "quantity": quantity,
                "value": float(value),
                "low": float(low),
                "high": float(high),
                "n_pixels": int(n_pixels),
                "reason": reason,
            }
        )

    residual = residual_correlation(
        stacks["left"],
        stacks["right"],
        disparity,
        sign=sign,
        masks=masks,
        valid=gl["valid"].transpose("y", "x").values,
        bands=DISPARITY_BANDS,
        settings=settings.bootstrap,
        min_pixels=settings.min_pixels,
    )
    for r in residual:
        quantity = RESIDUAL_QUANTITIES[r["alignment"]]
        if r["band"] != ALL_BANDS:
            quantity = f"{quantity}_{r['band']}"
        add(r["region"], quantity, r["rho"], r["low"], r["high"], r["n_pixels"], r["reason"])
    refs = {
        view: _reference(
            reference[view],
            loaded,
            images=stacks[view],
            seeds=seed_order[view],
            attrs=attrs[view],
            paths=paths_of[view],
            view=view,
        )
        for view in ("left", "right")
    }
    for region in regions:
        per_view = []
        for view in ("left", "right"):
            glass = gt.sel(view=view)["glass"].transpose("y", "x").values.astype(bool)
            mask = {"all": None, "glass": glass, "non_glass": ~glass}[region]
            per_view.append(refs[view](mask))
        pooled = _pooled_quality(per_view)
        for quantity in ("psnr", "mse", "relative_mse", "bias", "relative_bias"):
            add(
                region,
                quantity,
                pooled[quantity],
                n_pixels=pooled["n_pixels"],
                reason=pooled["reason"] if quantity == "psnr" else "",
            )
        add(region, "reference_noise", pooled["reference_noise"], n_pixels=pooled["n_pixels"])
    seconds = sum(float(a.get("transform_seconds", np.nan)) for a in attrs.values())
    mpix = sum(float(a.get("transform_megapixels", np.nan)) for a in attrs.values())
    add(
        "all",
        "transform_ms_per_mpix",
        1e3 * seconds / mpix if mpix > 0 else np.nan,
        reason="" if np.isfinite(seconds) else "renders not transformed",
    )
    write_tables(rows, MITIGATION_SCENE_COLUMNS, {"csv": out})
    for r in rows:
        if r["quantity"] in ("residual_rho_gt", "residual_rho_zero", "psnr"):
            log.info(
                "%s spp %d %-9s %-17s %.4f [%.4f, %.4f]%s",
                scene,
                spp,
                r["region"],
                r["quantity"],
                r["value"],
                r["low"],
                r["high"],
                f" [{r['reason']}]" if r["reason"] else "",
            )
    return rows


def _pooled_quality(per_view: list[dict]) -> dict:
    """Image quality of several views pooled by pixel count.

    MSE, relative MSE, bias, the reference noise and the reference mean are pixel-weighted
    means of the views'; the relative bias is the pooled bias over the pooled reference mean,
    and PSNR follows from the pooled MSE (:func:`stereovar.statistics.utility.image_quality`'s
    peak).
    """
    from ..statistics.utility import NOT_ABOVE_NOISE, PEAK

    nan = float("nan")
    weights = np.array([float(q["n_pixels"]) for q in per_view])
    keys = ("mse", "relative_mse", "bias", "reference_noise", "reference_mean")
    if weights.sum() == 0:
        return {
            **dict.fromkeys((*keys, "psnr", "relative_bias"), nan),
            "n_pixels": 0,
            "reason": per_view[0]["reason"],
        }
    w = weights / weights.sum()
    used = [(wi, q) for wi, q in zip(w, per_view, strict=True) if wi > 0]
    out = {k: float(sum(wi * float(q[k]) for wi, q in used)) for k in keys}
    ref = out["reference_mean"]
    out["relative_bias"] = out["bias"] / ref if ref else nan
    out.update(n_pixels=int(weights.sum()), reason="")
    if out["mse"] > 0:
        out["psnr"] = float(10 * np.log10(PEAK**2 / out["mse"]))
    else:
        out["psnr"] = nan
        out["reason"] = NOT_ABOVE_NOISE
    return out


def mitigations_table_job(
    runs: list[dict],
    outputs: dict,
    *,
    figure=None,
    nulls=None,
    calibration=(),
    headline=None,
) -> list[dict]:
    """``results/tables/mitigations.*`` and the trade-off figure from every mitigation's
    per-scene files (:func:`stereovar.statistics.mitigations.mitigation_table`).

    ``runs`` holds per mitigation ``mitigation``, ``kind``, ``description``, ``spp``, the
    ``calibration_transform`` whose matched null applies, and the paths ``correlation``,
    ``intervention`` and ``scene_rows`` (lists of CSVs); ``nulls`` is the calibration's
    matched-null table (``results/tables/calibration_nulls.csv``) and ``calibration`` every
    scene's calibration rows (their ``renders`` rows: what each transform ships);
    ``headline`` the paths of the headline table
    (:func:`stereovar.statistics.mitigations.headline_table`).
    """
    from ..io.tables import read_rows, write_tables
    from ..statistics.mitigations import MITIGATION_COLUMNS, mitigation_table

    loaded = []
    for run in runs:
        entry = {k: run[k] for k in ("mitigation", "kind", "description", "spp")}
        entry.update(
            {k: run[k] for k in ("render_spp", "aux_spp", "calibration_transform") if k in run}
        )
        for key in ("correlation", "intervention", "scene_rows"):
            entry[key] = [row for path in run.get(key, []) for row in read_rows(path)]
        loaded.append(entry)
    shipped = [
        r for path in calibration for r in read_rows(path) if r["kind"] == "renders"
    ]
    rows = mitigation_table(loaded, read_rows(nulls) if nulls else None, shipped=shipped)
    write_tables(
        rows,
        MITIGATION_COLUMNS,
        outputs,
        caption=(
            "Mitigations: the cue (rho and the intensity-controlled partial rho, with the null "
            "shift and simulated-sensor controls), its Monte Carlo-specific part (partial rho "
            "minus the matched null through the same transform) and verdict, Table 3 (C_sigma "
            "WTA lift over chance, "
            "C_eps shuffle effect), the cross-view residual correlation at the ground-truth "
            "alignment and at zero disparity, and the image quality against a converged "
            "reference; 95% intervals"
        ),
    )
    if headline:
        from ..statistics.mitigations import HEADLINE_COLUMNS, headline_table

        write_tables(
            headline_table(rows),
            HEADLINE_COLUMNS,
            headline,
            caption=(
                "Mitigations, all pixels: the Monte Carlo-specific rho (intensity-controlled "
                "rho minus its matched null through the same transform) with its 95% "
                "interval, that null, the same on what seed-mean transforms ship, the C_sigma "
                "lift over chance, PSNR against a raw render at the same samples per image, "
                "and the verdict (removed: inside the calibration's equivalence margin). "
                "The full table: mitigations.csv"
            ),
        )
    for row in rows:
        log.info(
            "%-15s %-9s partial %.3f, null %.3f, Monte Carlo-specific %.3f [%.3f, %.3f] %s, "
            "residual zero-disparity %.3f [%.3f, %.3f], PSNR %.2f dB [%.2f, %.2f]",
            row["mitigation"],
            row["region"],
            row["partial"],
            row["null_partial"],
            row["mc_specific"],
            row["mc_specific_low"],
            row["mc_specific_high"],
            row["mc_cue"],
            row["residual_rho_zero"],
            row["residual_rho_zero_low"],
            row["residual_rho_zero_high"],
            row["psnr"],
            row["psnr_low"],
            row["psnr_high"],
        )
    if figure is not None:
        from ..figures.mitigations import tradeoff_figure
        from .common import save_figure

        save_figure(tradeoff_figure(rows), figure)
    return rows
