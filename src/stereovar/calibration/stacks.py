"""Frame stacks through the run's transforms, as the transform job applies them to renders.

Each of :math:`N` frames of a view passes through a transform with the seed mean and variance
over all :math:`N` (:func:`transform_stack`); a transform that reads the seed mean is also
measured on what it ships, over disjoint groups of seeds (:func:`shipped_stack`).
"""

from __future__ import annotations

import numpy as np

from ..seeding import derive_seed

NONE = "none"
"""The identity transform: the statistics on the synthetic frames as drawn."""

SHIPPED = "|shipped"
"""Suffix of a transform's label when it is measured on what ships (:func:`shipped_stack`)."""


def transform_stack(
    name: str, frames, *, view: str, seed: int, aux=None, options=None, first_only=False
):
    """The run's transform ``name`` on each of :math:`N` frames of one view, as the
    transform job applies it to renders: every frame sees the seed mean and unbiased
    variance over all :math:`N` (:func:`stereovar.jobs.transform.seed_moments`'s
    definition), the view's auxiliary passes when given, and its own random seed.

    A chain ``a+b`` (:func:`stereovar.transforms.transform_chain`) applies each link to
    the previous link's :math:`N` outputs, as a store transform of a store transform would.

    Returns
    -------
    numpy.ndarray (N, H, W, C), float32
        Only the first frame's output (1, H, W, C) with ``first_only``.
    """
    if name == NONE:
        return frames
    from ..transforms import CHAIN, TransformInputs, get_transform

    if CHAIN in name:
        *links, last = name.split(CHAIN)
        for link in links:
            frames = transform_stack(link, frames, view=view, seed=derive_seed(seed, link),
                                     aux=aux, options=(options or {}).get(link))
        return transform_stack(last, frames, view=view, seed=derive_seed(seed, last), aux=aux,
                               options=(options or {}).get(last), first_only=first_only)
    t = get_transform(name)
    stack = np.asarray(frames, dtype=np.float64)
    mean = stack.mean(axis=0)
    var = stack.var(axis=0, ddof=1)
    extra = dict(aux or {})
    out = []
    for i, frame in enumerate(frames[:1] if first_only else frames):
        inputs = TransformInputs(
            render=np.asarray(frame, dtype=np.float32),
            view=view,
            seed_index=i,
            rng_seed=derive_seed(seed, view, i),
            seed_mean=mean,
            seed_var=var,
            n_seeds=len(frames),
            **extra,
        )
        out.append(t(inputs, **dict(options or {})))
    return np.stack(out)


def reads_seed_mean(name: str) -> bool:
    """Whether transform ``name`` builds its images from the seed statistics, so that Eq. 1
    over its :math:`N` outputs cannot see the Monte Carlo noise left in the seed mean."""
    if name == NONE:
        return False
    from ..transforms import transform_chain

    return any({"seed_mean", "seed_var"} & set(t.reads) for t in transform_chain(name))


def output_encoding_of(name: str) -> dict | None:
    """The integer encoding the last link of transform ``name`` writes (a generator's PNG,
    :mod:`stereovar.transforms.output`), or None for a float output."""
    if name == NONE:
        return None
    from ..transforms import transform_chain

    return transform_chain(name)[-1].encoding


def seed_groups(n: int, size: int = 2) -> list[np.ndarray]:
    """Disjoint groups of ``size`` consecutive seed indices among ``n`` (the last takes the
    rest); at least two groups, or none when :math:`n < 2\\,\\text{size}`.

    Examples
    --------
    >>> [g.tolist() for g in seed_groups(8)]
    [[0, 1], [2, 3], [4, 5], [6, 7]]
    >>> [g.tolist() for g in seed_groups(5)]
    [[0, 1], [2, 3, 4]]
    """
    count = n // size
    if count < 2:
        return []
    return np.array_split(np.arange(count * size), count)[:-1] + [
        np.arange((count - 1) * size, n)
    ]


def shipped_stack(name: str, frames, *, view: str, seed: int, aux=None, options=None, size=2):
    """What a transform that reads the seed mean ships, over independent repetitions.

    The :math:`N` frames are split into :math:`G = \\lfloor N/k \\rfloor` disjoint groups of
    :math:`k` (``size``, :func:`seed_groups`); each group is transformed with its own seed
    mean :math:`\\bar I_g` and variance, and its first image kept, so the :math:`G` images
    are independent repetitions of the shipped image:

    .. math::

        I'_g = T\\bigl(I^{(n_g)};\\ \\bar I_g, \\hat\\sigma^2_g\\bigr), \\qquad
        \\operatorname{Var}_g[I'_g] = \\operatorname{Var}[\\bar I_g] + \\text{camera}
            = \\frac{\\sigma^2}{k} + a\\mu + b

    and Eq. 1 over them sees the Monte Carlo noise the seed mean carries
    (:math:`\\sigma^2/k` here, :math:`\\sigma^2/N` in the images a team ships, so the remnant
    is shown :math:`N/k` times stronger relative to the camera noise than it ships).

    Returns
    -------
    numpy.ndarray (G, H, W, C), float32
        Empty (G = 0) when :math:`N < 2k`.
    """
    groups = seed_groups(len(frames), size)
    images = [
        transform_stack(
            name, np.asarray(frames)[g], view=view, seed=derive_seed(seed, "group", i),
            aux=aux, options=options, first_only=True,
        )[0]
        for i, g in enumerate(groups)
    ]
    return np.stack(images) if images else np.empty((0, *np.shape(frames)[1:]), np.float32)
