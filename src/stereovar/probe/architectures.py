"""The probe's networks, one registry entry each: how it trains, how it predicts, what it reads.

``mccnn``
    MC-CNN "fast" (Žbontar & LeCun 2016; :mod:`~stereovar.probe.network`): a 9x9-patch
    siamese matcher, winner-take-all over a learned cost; trained on triplets.
``costvolume``
    A small end-to-end cost-volume network (:mod:`~stereovar.probe.costvolume`): 2-D
    features, a cost volume, 3-D convolution and soft-argmin, the design of the networks
    teams train today (StereoNet, AnyNet), at under 0.5 M parameters; trained on the
    disparity itself.

Both read one render per view as the matcher's input (standardised display grey,
:func:`stereovar.probe.inputs.network_input`) and the left view's ground-truth disparity on
the scored set; both train on :class:`~stereovar.probe.training.TrainingFrame` and predict a
batch of pairs at once.

Importing this module pulls in no third-party package; an entry imports PyTorch when used.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import import_module

__all__ = ["ARCHITECTURE_ENTRIES", "Architecture", "architecture"]


@dataclass(frozen=True)
class Architecture:
    """One probe network: its ``name``, a ``label`` for tables, the module that holds it, the
    names of its settings class, training function and batched prediction function
    (``module:name`` where it lives in another module), the
    config key of its settings, and what it ``reads``."""

    name: str
    label: str
    module: str
    settings_class: str
    train_function: str
    predict_function: str
    config_key: str
    reads: tuple = ("left render", "right render", "left disparity")

    def _get(self, attr: str):
        module, _, name = attr.rpartition(":")
        return getattr(import_module(module or self.module), name)

    def settings(self, options: dict | None = None):
        """The training settings from their config section (``probe.<config_key>``)."""
        return self._get(self.settings_class)(**dict(options or {}))

    def train(self, frames, settings, *, seed: int, device="cpu", validation=None):
        """``(net, history)`` of one trained network (on the CPU when it returns)."""
        return self._get(self.train_function)(
            frames, settings, seed=int(seed), device=device, validation=validation
        )

    def predict(self, net, pairs, *, sign: int, max_disparity: int) -> list:
        """:math:`\\hat d` (H, W) of every (left, right) network-input pair, NaN where the
        network gives none."""
        return self._get(self.predict_function)(
            net, pairs, sign=int(sign), max_disparity=int(max_disparity)
        )


ARCHITECTURE_ENTRIES = {
    "mccnn": Architecture(
        "mccnn",
        "MC-CNN fast (WTA)",
        "stereovar.probe.training",
        "TrainSettings",
        "train_matcher",
        "stereovar.probe.network:predict_matcher",
        "training",
    ),
    "costvolume": Architecture(
        "costvolume",
        "cost volume (3-D conv, soft-argmin)",
        "stereovar.probe.costvolume",
        "CostVolumeSettings",
        "train_costvolume",
        "predict_costvolume",
        "costvolume",
    ),
}


def architecture(name: str) -> Architecture:
    """The registry entry ``name``.

    Raises
    ------
    ValueError
        An unknown name, with the choices listed.

    Examples
    --------
    >>> architecture("mccnn").label
    'MC-CNN fast (WTA)'
    """
    try:
        return ARCHITECTURE_ENTRIES[str(name)]
    except KeyError:
        raise ValueError(
            f"unknown probe architecture {name!r}; use one of {', '.join(ARCHITECTURE_ENTRIES)}"
        ) from None
