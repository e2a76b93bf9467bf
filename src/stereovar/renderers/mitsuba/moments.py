"""Per-pixel sample moments of one render: a Mitsuba integrator that wraps another.

Mitsuba's own ``moment`` integrator writes its second moments in XYZ in the RGB variants;
the single-render estimator (:mod:`stereovar.estimators.moments`) needs them per RGB
channel. :class:`MomentIntegrator` wraps the configured integrator (``path``) and returns,
beside its radiance, seven AOVs per sample :math:`f = (f_R, f_G, f_B)`:

.. math::

    \\mathbb 1_{\\text{finite}}\\, f_c, \\qquad \\mathbb 1_{\\text{finite}}\\, f_c^2,
    \\qquad \\mathbb 1_{\\text{finite}},

where :math:`\\mathbb 1_{\\text{finite}}` is 1 when every channel of the sample is finite.
Under a box reconstruction filter every sample lands in its own pixel with weight 1, so the
film's average of each AOV over the pixel's :math:`s` samples is :math:`\\frac1s \\sum f_c`,
:math:`\\frac1s \\sum f_c^2` and the finite fraction :math:`n/s`. Wrapping costs no extra
path: the nested integrator's ``sample`` is called once per sample, as ``mi.render`` would.
"""

from __future__ import annotations

import numpy as np

from ..base import SampleMoments

PLUGIN = "stereovar_moments"
"""Name the integrator is registered under (per variant, on first use)."""

AOVS = ("m1.R", "m1.G", "m1.B", "m2.R", "m2.G", "m2.B", "finite")
"""The AOV channels, in the order the film returns them after R, G, B."""

_registered: set[str] = set()


def register(mi) -> str:
    """Register :class:`MomentIntegrator` for Mitsuba's current variant; returns the plugin
    name."""
    variant = mi.variant()
    if variant in _registered:
        return PLUGIN
    import drjit as dr

    class MomentIntegrator(mi.SamplingIntegrator):
        """Radiance of the nested integrator plus its per-sample moments as AOVs."""

        def __init__(self, props):
            super().__init__(props)
            self.nested = props["integrator"]

        def aov_names(self):
            return list(AOVS)

        def sample(self, scene, sampler, ray, medium=None, active=True):
            spec, valid, _ = self.nested.sample(scene, sampler, ray, medium, active)
            rgb = mi.Color3f(spec)
            ok = dr.isfinite(rgb[0]) & dr.isfinite(rgb[1]) & dr.isfinite(rgb[2])
            f = dr.select(ok, rgb, 0.0)
            aovs = [f[0], f[1], f[2], f[0] * f[0], f[1] * f[1], f[2] * f[2]]
            return spec, valid, [*aovs, dr.select(ok, mi.Float(1.0), mi.Float(0.0))]

        def to_string(self):
            return f"MomentIntegrator[nested={self.nested}]"

    mi.register_integrator(PLUGIN, lambda props: MomentIntegrator(props))
    _registered.add(variant)
    return PLUGIN


def moment_integrator_dict(nested: dict) -> dict:
    """The integrator dict of :class:`MomentIntegrator` around ``nested`` (an integrator
    dict, e.g. :func:`~stereovar.renderers.mitsuba.sensor.integrator_dict`)."""
    return {"type": PLUGIN, "integrator": dict(nested)}


def film_moments(image, spp: int) -> SampleMoments:
    """Sample moments from the film of a :class:`MomentIntegrator` render.

    Parameters
    ----------
    image : array_like, shape (H, W, 3 + len(AOVS)) or (H, W, 4 + len(AOVS))
        ``mi.render`` output: R, G, B (and A when the film has alpha), then :data:`AOVS`.
    spp : int
        Samples per pixel of the render.

    Returns
    -------
    SampleMoments
        Per-pixel mean of :math:`f_c` and of :math:`f_c^2` over the finite samples (0 where
        there is none) and their count.
    """
    a = np.asarray(image, dtype=np.float32)
    aov = a[..., -len(AOVS) :]
    count = np.rint(aov[..., 6].astype(np.float64) * int(spp)).astype(np.int32)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(count > 0, int(spp) / np.maximum(count, 1), 0.0)[..., None]
    return SampleMoments(
        mean=(aov[..., 0:3] * scale).astype(np.float32),
        mean_sq=(aov[..., 3:6] * scale).astype(np.float32),
        count=count,
    )
