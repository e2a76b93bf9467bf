"""The probe's cross-validation over scenes: which scenes each fold trains on and holds out.

Standard library only, so the workflow reads the folds without importing PyTorch.
"""

from __future__ import annotations

__all__ = ["fold_scenes"]


def fold_scenes(scenes, folds: int) -> list[tuple[list[str], list[str]]]:
    """``(training scenes, held-out scenes)`` of each fold.

    Raises
    ------
    ValueError
        Fewer than 2 folds, or more folds than scenes.

    Examples
    --------
    >>> fold_scenes(["a", "b", "c"], 2)
    [(['b'], ['a', 'c']), (['a', 'c'], ['b'])]
    """
    scenes = list(scenes)
    folds = int(folds)
    if folds < 2 or folds > len(scenes):
        raise ValueError(
            f"probe.folds is {folds} with {len(scenes)} scenes; cross-validation needs "
            "2 <= folds <= scenes (add scenes or frames, or lower probe.folds)"
        )
    held = [[s for i, s in enumerate(scenes) if i % folds == f] for f in range(folds)]
    return [([s for s in scenes if s not in held[f]], held[f]) for f in range(folds)]
