"""Jobs that make a mitigation's images (``workflow/rules/mitigations.smk``): the auxiliary
passes a denoiser reads, and store transforms applied to a view's renders."""

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
