"""What every workflow job shares: logging, scene preparation and figure saving.

The modules of :mod:`stereovar.jobs` hold one function per workflow job, one module per
``workflow/rules/*.smk`` file; the Snakemake scripts in ``workflow/scripts`` are thin adapters
that call them, so every job also runs from a notebook or a shell without Snakemake.
"""

from __future__ import annotations

import logging
import sys
import time
from pathlib import Path

from ..errors import StereovarError

log = logging.getLogger("stereovar")


def run_job(log_path, job, **kwargs) -> None:
    """Run ``job(**kwargs)`` with logging to ``log_path`` and to stderr.

    A :class:`~stereovar.errors.StereovarError` becomes one ``error:`` line on stderr and in
    the log, and exit status 1, without a traceback. Any other exception is a defect: its
    traceback goes to stderr and to the log, so a failed job's log is never empty, and the
    exit status is 1.
    """
    handlers = [logging.StreamHandler(sys.stderr)]
    if log_path:
        Path(log_path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(log_path, mode="w"))
    logging.basicConfig(
        level=logging.INFO,
        format="%(asctime)s %(levelname)s %(message)s",
        handlers=handlers,
        force=True,
    )
    start = time.perf_counter()
    try:
        job(**kwargs)
    except StereovarError as err:
        log.error("error: %s", err)
        raise SystemExit(1) from None
    except Exception as err:
        log.exception("error: unexpected %s: %s", type(err).__name__, err)
        raise SystemExit(1) from None
    log.info("done in %.2f s", time.perf_counter() - start)


def prepare_scene(
    spec_path, *, renderer: str = "mitsuba", variant: str = "auto", threads=None, **rig
):
    """Load a spec and compile it with ``renderer`` for the rig.

    Parameters
    ----------
    spec_path : path-like
        The scene spec.
    renderer, variant : str, keyword-only
        ``render.renderer`` and ``render.variant``.
    threads : int, keyword-only, optional
        Render threads.
    **rig
        ``width``, ``height``, ``baseline_m``, ``convention``
        (:func:`stereovar.rig.make_rig`).

    Returns
    -------
    stereovar.renderers.base.PreparedScene
        The compiled scene, its rig and its provenance attrs.
    """
    from ..renderers import get_renderer
    from ..scenes.spec import load_scene_spec

    spec = load_scene_spec(spec_path)
    return get_renderer(renderer).prepare(spec, rig=rig, variant=variant, threads=threads)


RIG_KEYS = ("width", "height", "baseline_m", "convention")
"""Job options that build the stereo rig (:func:`stereovar.rig.make_rig`)."""


def render_options(options: dict):
    """Split a render job's options into the rig and the render settings.

    Returns
    -------
    rig : dict
        The :data:`RIG_KEYS` entries.
    settings : stereovar.renderers.base.RenderSettings
        From the rest (``integrator``, ``max_depth``, ``rfilter``, ``sampler``).
    """
    from ..renderers.base import RenderSettings

    rig = {k: options[k] for k in RIG_KEYS if k in options}
    return rig, RenderSettings(**{k: v for k, v in options.items() if k not in RIG_KEYS})


def save_figure(fig, out, *, dpi: int = 120) -> None:
    """Save a matplotlib figure as PNG atomically and close it."""
    import matplotlib.pyplot as plt

    from ..io.store import write_file

    write_file(out, lambda tmp: fig.savefig(tmp, format="png", dpi=dpi))
    plt.close(fig)


def left_right(ds, name):
    """``ds[name]`` of the left and of the right view."""
    return ds[name].sel(view="left"), ds[name].sel(view="right")


def run_label(renderer: str, estimator: str | None = None) -> str:
    """``renderer mitsuba, estimator seeds``: which renders a table or figure shows; an
    audit's imported renders (renderer ``audit/{name}``) as ``audit {name}``.

    Examples
    --------
    >>> run_label("mitsuba", "seeds"), run_label("audit/team_v2", "seeds")
    ('renderer mitsuba, estimator seeds', 'audit team_v2')
    """
    if str(renderer).startswith("audit/"):
        return f"audit {str(renderer).split('/', 1)[1]}"
    text = f"renderer {renderer}"
    return f"{text}, estimator {estimator}" if estimator else text


def run_of(rows: list[dict]) -> dict:
    """The ``renderer`` and ``estimator`` that every row names (one of each, when named).

    Raises
    ------
    ValueError
        The rows mix several renderers or estimators.
    """
    out = {}
    for key in ("renderer", "estimator"):
        values = sorted({str(r[key]) for r in rows if r.get(key) not in (None, "")})
        if len(values) > 1:
            raise ValueError(f"rows mix several {key}s: {values}")
        if values:
            out[key] = values[0]
    return out


def view_stack(paths) -> tuple:
    """Every render of one view's stores: ``(stack (N, H, W, 3), seed indices, sampler
    seeds, attrs of the first store)``."""
    import numpy as np

    from ..io.store import load_store

    stacks, seeds, samplers, attrs = [], [], [], None
    for path in paths:
        ds = load_store(path, "render store", ["radiance"])
        stacks.append(ds["radiance"].transpose("seed", "y", "x", "channel").values)
        seeds += [int(s) for s in ds["seed"].values]
        samplers += [int(s) for s in ds["sampler_seed"].values]
        attrs = attrs or dict(ds.attrs)
    return np.concatenate(stacks), np.asarray(seeds), np.asarray(samplers), attrs
