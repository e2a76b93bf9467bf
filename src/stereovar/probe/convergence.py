"""Training to convergence: a plateau of validation accuracy on held-out frames.

Every ``check_every`` steps a training loop scores its network on held-out frames (one seed
index per held-out scene) and feeds the accuracy to a :class:`Plateau`. The accuracy is the
share of scored pixels whose prediction lies within one pixel of the truth (the probe's hit,
:mod:`stereovar.probe.scoring`):

.. math::

    A_t = \\frac{1}{|\\Omega|} \\sum_{p \\in \\Omega} [\\,|\\hat d_t(p) - d(p)| < 1\\,].

The loop stops at check :math:`t` once ``patience`` checks in a row have not beaten the best
accuracy so far by more than ``min_delta``, and not before ``min_steps`` steps; it then keeps
the weights of the best check (early stopping; Prechelt 1998, "Early stopping - but when?").
Both probe architectures share this rule and :func:`validation_accuracy`, which takes the
architecture's batched prediction as a callable.

Importing this module pulls in only numpy.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = [
    "VALIDATION_SEED",
    "Plateau",
    "PlateauSettings",
    "StopRule",
    "fixed_frames",
    "train_to_plateau",
    "validation_accuracy",
]

VALIDATION_SEED = 0
"""Seed of the one draw of a validation frame's right input (a twin's shuffled residual)."""


@dataclass(frozen=True)
class StopRule:
    """When a training loop stops: a validation check every ``check_every`` steps; stop after
    ``patience`` checks in a row without an accuracy gain above ``min_delta`` (a share, 0.002
    = 0.2 points) over the best so far, and not before ``min_steps`` steps.

    Examples
    --------
    >>> StopRule().patience
    4
    >>> StopRule(check_every=0)
    Traceback (most recent call last):
    ...
    ValueError: the stop rule's check_every must be >= 1, got 0
    """

    check_every: int = 25
    patience: int = 4
    min_delta: float = 0.002
    min_steps: int = 100

    def __post_init__(self):
        for name in ("check_every", "patience"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"the stop rule's {name} must be >= 1, got {getattr(self, name)}")
        if int(self.min_steps) < 0:
            raise ValueError(f"the stop rule's min_steps must be >= 0, got {self.min_steps}")
        if not float(self.min_delta) >= 0:
            raise ValueError(f"the stop rule's min_delta must be >= 0, got {self.min_delta}")


@dataclass
class Plateau:
    """The state of a :class:`StopRule` over one training: the checks seen, the best step and
    its accuracy.

    A check improves when :math:`A_t > A_{best} + \\delta`; the best step moves only then (a
    gain within :math:`\\delta` is noise, so the earlier, equally good weights are kept).

    Examples
    --------
    >>> p = Plateau(StopRule(check_every=10, patience=2, min_delta=0.01, min_steps=0))
    >>> [p.update(s, a) for s, a in [(10, 0.5), (20, 0.7), (30, 0.705), (40, 0.69)]]
    [False, False, False, True]
    >>> p.best_step, p.best_accuracy
    (20, 0.7)
    """

    rule: StopRule = field(default_factory=StopRule)
    best_step: int | None = None
    best_accuracy: float = -np.inf
    history: list = field(default_factory=list)
    stale: int = 0

    def update(self, step: int, accuracy: float) -> bool:
        """Record the validation ``accuracy`` at ``step``; True when training should stop.

        Returns
        -------
        bool
            ``patience`` checks in a row without an improvement, and ``step >= min_steps``.
        """
        step, accuracy = int(step), float(accuracy)
        self.history.append((step, accuracy))
        if self.best_step is None or accuracy > self.best_accuracy + float(self.rule.min_delta):
            self.best_step, self.best_accuracy, self.stale = step, accuracy, 0
            return False
        self.stale += 1
        return self.stale >= int(self.rule.patience) and step >= int(self.rule.min_steps)

    def improved(self) -> bool:
        """Whether the last check set a new best (the loop then keeps these weights)."""
        return bool(self.history) and self.history[-1][0] == self.best_step


@dataclass(frozen=True)
class PlateauSettings:
    """The stop-rule fields of an architecture's training settings (``probe.training``,
    ``probe.costvolume``): a check every ``check_every`` steps, ``patience`` checks without a
    gain above ``min_delta``, not before ``min_steps``."""

    check_every: int = 25
    patience: int = 4
    min_delta: float = 0.002
    min_steps: int = 100

    def stop_rule(self) -> StopRule:
        """The :class:`StopRule` of these settings (which checks its fields)."""
        return StopRule(
            check_every=int(self.check_every),
            patience=int(self.patience),
            min_delta=float(self.min_delta),
            min_steps=int(self.min_steps),
        )


def fixed_frames(frames: Sequence, seed: int = VALIDATION_SEED) -> list:
    """The frames with their right input drawn once: a frame with a ``redraw`` (a twin's)
    gets ``redraw`` of one generator seeded ``seed`` (in frame order) as its fixed right input,
    so every check scores the same pairs.

    Examples
    --------
    >>> from stereovar.probe.training import TrainingFrame
    >>> z = np.zeros((2, 2), np.float32)
    >>> f = TrainingFrame(z, z, z, -1, redraw=lambda rng: z + rng.integers(1, 9))
    >>> fixed = fixed_frames([f])
    >>> fixed[0].redraw is None, bool((fixed[0].right == fixed_frames([f])[0].right).all())
    (True, True)
    """
    rng = np.random.default_rng(int(seed))
    out = []
    for frame in frames:
        if getattr(frame, "redraw", None) is None:
            out.append(frame)
        else:
            right = np.asarray(frame.right_input(rng), dtype=np.float32)
            out.append(replace(frame, right=right, redraw=None))
    return out


def validation_accuracy(
    predict: Callable[..., list], frames: Sequence, *, max_disparity: int
) -> float:
    """Share of the validation frames' scored pixels predicted within one pixel.

    .. math::

        A = \\frac{\\sum_f \\sum_{p \\in \\Omega_f} [\\,|\\hat d_f(p) - d_f(p)| < 1\\,]}
                 {\\sum_f |\\Omega_f|},

    pooled over frames; :math:`\\Omega_f` is the frame's pixels with a ground truth
    :math:`d \\le D`, and a pixel without a prediction (the network's border) counts as a miss.

    Parameters
    ----------
    predict : callable
        ``predict(pairs, *, sign, max_disparity) -> list of (H, W) arrays``: the architecture's
        batched prediction with its network bound, e.g.
        ``functools.partial(predict_matcher, net)``.
    frames : sequence of TrainingFrame
        Held-out frames; a frame with a ``redraw`` gets its right input drawn once
        (:func:`fixed_frames`, seed :data:`VALIDATION_SEED`).
    max_disparity : int, keyword-only
        :math:`D`.

    Returns
    -------
    float
        :math:`A` in [0, 1]; NaN when no frame has a scored pixel.

    Examples
    --------
    >>> from stereovar.probe.training import TrainingFrame
    >>> d = np.array([[1.0, 2.0, np.nan, 3.0]], np.float32)
    >>> frame = TrainingFrame(np.zeros_like(d), np.zeros_like(d), d, -1)
    >>> guess = lambda pairs, *, sign, max_disparity: [np.full((1, 4), 2.4) for _ in pairs]
    >>> validation_accuracy(guess, [frame], max_disparity=5)
    0.6666666666666666
    """
    frames = fixed_frames(frames)
    hits, total = 0, 0
    for sign in sorted({int(f.sign) for f in frames}):
        group = [f for f in frames if int(f.sign) == sign]
        preds = predict(
            [(f.left, f.right) for f in group], sign=sign, max_disparity=int(max_disparity)
        )
        for frame, d_hat in zip(group, preds, strict=True):
            d = np.asarray(frame.disparity, dtype=np.float64)
            scored = np.isfinite(d) & (d <= int(max_disparity))
            err = np.abs(np.asarray(d_hat, dtype=np.float64)[scored] - d[scored])
            hits += int(np.count_nonzero(err < 1))  # NaN (no prediction) compares False
            total += int(np.count_nonzero(scored))
    return hits / total if total else float("nan")


def train_to_plateau(
    net, step: Callable, *, steps: int, rule: StopRule, held, predict: Callable,
    max_disparity: int,
) -> dict:
    """The training loop both probe architectures share: ``step(i)`` for
    :math:`i = 1, \\dots,` ``steps``; every ``rule.check_every`` steps (and at the last) the
    accuracy of ``predict(net, ...)`` on the ``held`` frames (:func:`validation_accuracy`)
    feeds a :class:`Plateau`, which may stop the loop; the network then gets back the weights
    of its best check. Without ``held`` frames it runs every step.

    Parameters
    ----------
    net : torch.nn.Module
        Put in training mode before each step.
    step : callable
        One optimiser step, given its number.
    steps : int
        The cap.
    rule : StopRule
    held : sequence
        Validation frames (:func:`fixed_frames`), or empty.
    predict : callable
        The architecture's batched prediction, ``predict(net, pairs, *, sign, max_disparity)``.
    max_disparity : int
        :math:`D` of the checks.

    Returns
    -------
    dict
        ``seconds`` of the loop, ``step_seconds`` (per step, checks excluded), ``steps``
        taken, ``best_step`` (the step whose weights the network holds), ``validation`` as
        ``(step, accuracy)`` per check and ``validation_seconds``.
    """
    plateau = Plateau(rule)
    best_state = None
    check_seconds = 0.0
    start = time.perf_counter()
    i = 0
    for i in range(1, int(steps) + 1):
        net.train()
        step(i)
        if held and (i % int(rule.check_every) == 0 or i == int(steps)):
            t0 = time.perf_counter()
            accuracy = validation_accuracy(
                lambda pairs, **kw: predict(net, pairs, **kw), held, max_disparity=max_disparity
            )
            stop = plateau.update(i, accuracy)
            if plateau.improved():
                best_state = {k: v.detach().clone() for k, v in net.state_dict().items()}
            check_seconds += time.perf_counter() - t0
            if stop:
                break
    seconds = time.perf_counter() - start
    if best_state is not None:
        net.load_state_dict(best_state)
    return {
        "seconds": seconds,
        "step_seconds": (seconds - check_seconds) / max(i, 1),
        "steps": int(i),
        "best_step": int(plateau.best_step if plateau.best_step is not None else i),
        "validation": list(plateau.history),
        "validation_seconds": check_seconds,
    }
