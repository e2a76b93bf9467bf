"""The renderer protocol: what every renderer behind ``render.renderer`` provides.

A renderer compiles a renderer-neutral scene spec (:mod:`stereovar.scenes.spec`) for the
stereo rig, renders one view with an explicit seed and sample count, traces one ray through
each pixel centre for the ground truth, and reports its provenance. Everything renderer-neutral
(the rig, correspondence, occlusion, the stored contracts, the statistics) stays outside, so a
second renderer is one new subpackage plus one registry entry
(:data:`stereovar.renderers.RENDERERS`) and one value of the config schema's
``render.renderer`` enum.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, NamedTuple


@dataclass(frozen=True)
class RenderSettings:
    """Renderer settings shared by every render of a job.

    Attributes
    ----------
    integrator : str
        Integrator name (``path`` for a unidirectional path tracer).
    max_depth : int
        Longest path, in bounces (-1 unbounded).
    rfilter : str
        Reconstruction filter (``box``: a pixel's variance is its own estimator's).
    sampler : str
        Sampler (``independent``).
    renderer_options : dict
        Options only one renderer reads (``render.cycles`` for Cycles).
    """

    integrator: str = "path"
    max_depth: int = 8
    rfilter: str = "box"
    sampler: str = "independent"
    renderer_options: dict = field(default_factory=dict)

    def as_attrs(self) -> dict:
        """The settings as store attributes."""
        attrs = {
            "integrator": self.integrator,
            "max_depth": int(self.max_depth),
            "rfilter": self.rfilter,
            "sampler": self.sampler,
        }
        if self.renderer_options:
            import json

            attrs["renderer_options"] = json.dumps(self.renderer_options, sort_keys=True)
        return attrs


class FirstHits(NamedTuple):
    """One ray through each pixel centre of one view, intersected with the scene.

    Attributes
    ----------
    hit : numpy.ndarray, shape (H, W), bool
        The ray hit a shape the renderer knows.
    points : numpy.ndarray, shape (H, W, 3), float64
        First-hit points in world space (undefined where not ``hit``).
    normals : numpy.ndarray, shape (H, W, 3), float64
        Geometric normals at the hits.
    shape_index : numpy.ndarray, shape (H, W), int32
        Index into :meth:`PreparedScene.shape_materials`; -1 where not ``hit``.
    """

    hit: Any
    points: Any
    normals: Any
    shape_index: Any


class SampleMoments(NamedTuple):
    """Per-pixel moments of one render's samples (the single-render estimator's input).

    Attributes
    ----------
    mean : numpy.ndarray, shape (H, W, 3), float32
        :math:`\\frac1n \\sum_k f_{k,c}` over the pixel's finite samples (0 where none).
    mean_sq : numpy.ndarray, shape (H, W, 3), float32
        :math:`\\frac1n \\sum_k f_{k,c}^2` over the same samples.
    count : numpy.ndarray, shape (H, W), int32
        :math:`n`, the samples with every channel finite.
    """

    mean: Any
    mean_sq: Any
    count: Any

    CHANNELS = ("R", "G", "B", "R2", "G2", "B2", "n")
    """Channel names of :meth:`stack`."""

    def stack(self):
        """The moments as one float32 (H, W, 7) array (channels :attr:`CHANNELS`)."""
        import numpy as np

        return np.concatenate(
            [self.mean, self.mean_sq, np.asarray(self.count, np.float32)[..., None]], axis=-1
        ).astype(np.float32)

    @classmethod
    def from_stack(cls, array) -> SampleMoments:
        """Inverse of :meth:`stack`."""
        import numpy as np

        a = np.asarray(array, dtype=np.float32)
        if a.ndim != 3 or a.shape[-1] != len(cls.CHANNELS):
            raise ValueError(f"sample moments must have shape (H, W, 7), got {a.shape}")
        return cls(a[..., 0:3], a[..., 3:6], np.rint(a[..., 6]).astype(np.int32))


@dataclass
class PreparedScene(ABC):
    """A scene compiled by one renderer for one stereo rig, ready to render and trace.

    Attributes
    ----------
    rig : stereovar.rig.StereoRig
        The stereo rig (the scene camera as the left view).
    spec : dict
        The renderer-neutral spec it was compiled from (empty when built from a loaded scene).
    provenance : dict
        Store attributes: ``scene``, ``scene_digest``, ``renderer``, ``renderer_version``,
        ``variant``, ``stereovar_version`` and any renderer-specific versions.
    """

    rig: Any
    spec: dict = field(default_factory=dict)
    provenance: dict = field(default_factory=dict)

    @abstractmethod
    def render(self, view: str, *, spp: int, seed: int, settings: RenderSettings):
        """Render ``view`` (``"left"`` or ``"right"``) of the rig.

        Returns
        -------
        numpy.ndarray, shape (H, W, 3), float32
            Linear RGB radiance, with ``seed`` passed to the renderer's sampler unchanged.
        """

    def render_moments(
        self, view: str, *, spp: int, seed: int, settings: RenderSettings
    ) -> SampleMoments:
        """Render ``view`` once and return its per-pixel sample moments (the ``moments``
        estimator, :mod:`stereovar.estimators.moments`) instead of its image.

        Raises
        ------
        stereovar.errors.ConfigError
            The renderer cannot return per-sample moments.
        """
        from ..errors import ConfigError

        raise ConfigError(
            f"renderer '{self.provenance.get('renderer', type(self).__name__)}' has no "
            "per-sample moments; set render.estimator: seeds"
        )

    def render_aux(self, view: str, *, spp: int, seed: int) -> tuple:
        """Render ``view``'s auxiliary passes for a denoiser: the first hit's albedo and its
        shading normal, each averaged over ``spp`` samples.

        Returns
        -------
        albedo, normal : numpy.ndarray, shape (H, W, 3), float32
            Albedo in [0, 1]; world-space shading normal (zero where nothing is hit).

        Raises
        ------
        stereovar.errors.ConfigError
            The renderer has no auxiliary passes.
        """
        from ..errors import ConfigError

        raise ConfigError(
            f"renderer '{self.provenance.get('renderer', type(self).__name__)}' renders no "
            "albedo or normal pass; the denoise mitigations run on its renders without them"
        )

    @abstractmethod
    def trace(self, view: str) -> FirstHits:
        """First hits of one ray through each pixel centre of ``view``."""

    @abstractmethod
    def shape_materials(self) -> tuple[Any, list[str]]:
        """Material class code (an index into
        :data:`stereovar.ground_truth.MATERIAL_CLASSES`, uint8) and id of every shape, in the
        order :attr:`FirstHits.shape_index` refers to."""


class Renderer(ABC):
    """A renderer: compiles scene specs into :class:`PreparedScene` objects.

    Subclasses set :attr:`name` (the ``render.renderer`` value) and implement
    :meth:`prepare`.
    """

    name: str = ""
    sample_moments: bool = False
    """Whether :meth:`PreparedScene.render_moments` works (the ``moments`` estimator, and the
    mitigations' converged reference)."""
    aux_passes: tuple[str, ...] = ()
    """The auxiliary passes :meth:`PreparedScene.render_aux` gives (``albedo``, ``normal``),
    read by the denoise mitigations; empty when it gives none."""

    def seed_policy(self, policy: str, options: dict | None = None) -> str:
        """The seed policy (:data:`stereovar.seeding.SEED_POLICIES`) a job's renders take
        under ``policy`` and the renderer's own ``options``: ``policy`` itself, unless the
        renderer has a seed rule of its own that shares the views' seeds."""
        return policy

    def sampler_seed(self, scene: str, view: str, spp, index, *, policy: str, options=None):
        """The sampler seed of render ``index`` of ``view``, as stored with the render:
        :func:`stereovar.seeding.render_seed` under ``policy``, unless the renderer derives
        it from its own ``options``."""
        from ..seeding import render_seed

        return render_seed(scene, view, spp, index, policy=policy)

    def backend(self, variant: str = "auto") -> dict:
        """The back end a render with ``variant`` uses on this machine, found without
        compiling a scene: part of every render's cache key and provenance.

        Returns
        -------
        dict
            ``renderer``, ``renderer_version``, the resolved ``variant`` (never
            ``auto``) and ``jit_target`` (the CPU target kernels are compiled for, where
            the renderer compiles for one, else empty), plus any renderer-specific
            versions; strings.

        Raises
        ------
        BackendError
            ``variant`` is unknown or unavailable here (one line).
        """
        return {
            "renderer": self.name,
            "renderer_version": "",
            "variant": variant,
            "jit_target": "",
        }

    @abstractmethod
    def prepare(
        self, spec: dict, *, rig: dict, variant: str = "auto", threads: int | None = None
    ) -> PreparedScene:
        """Compile a validated spec and build the rig around its camera.

        Parameters
        ----------
        spec : dict
            A validated scene spec (:func:`stereovar.scenes.spec.load_scene_spec`).
        rig : dict
            ``width``, ``height`` (pixels), ``baseline_m`` and ``convention`` (``paper`` or
            ``conventional``), passed to :func:`stereovar.rig.make_rig` with the scene camera.
        variant : str
            Renderer back end (``auto`` picks the best available).
        threads : int, optional
            Worker threads.
        """


def scene_provenance(spec: dict, backend: dict) -> dict:
    """Store attributes of everything rendered or traced from ``spec`` with ``backend``
    (:meth:`Renderer.backend`): ``scene``, ``scene_digest`` (the spec and every file it
    reads), the back end and ``stereovar_version``."""
    from .. import __version__
    from ..scenes.spec import scene_digest

    return {
        "scene": spec["name"],
        "scene_digest": scene_digest(spec),
        **backend,
        "stereovar_version": __version__,
    }
