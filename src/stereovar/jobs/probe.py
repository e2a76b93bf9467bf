"""Jobs of ``workflow/rules/probe.smk``: train one probe network, test every network of a
fold on its held-out scenes, and write the probe table, figure and verdict."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from .common import log, view_stack

PROBE_REGIONS = ("all", "non_glass", "glass")
"""Regions scored (``all`` only where the ground truth has no glass pixel)."""


def _scene(stores: dict, scene: str):
    """The renders (N, H, W, 3) of each view, the ground truth of each view (``disparity``,
    ``valid``, ``glass``) and the sign."""
    from ..io.store import load_store

    left = view_stack(stores[f"left_{scene}"])[0]
    right = view_stack(stores[f"right_{scene}"])[0]
    gt = load_store(stores[f"gt_{scene}"], "ground-truth store", ["disparity", "valid", "glass"])
    sign = int(gt.attrs["disparity_sign"])
    truths = {
        view: {
            k: gt[k].sel(view=view).transpose("y", "x").values
            for k in ("disparity", "valid", "glass")
        }
        for view in ("left", "right")
    }
    return left, right, truths, sign


def planted_job(stores: dict, out, *, scenes, factors) -> dict:
    """The planted control's settings measured on the renders (``none``): each scene's camera
    law and strength (:func:`stereovar.probe.planted.renders_strength`), and the renders'
    strength, the median over scenes, which the factors of ``probe.planted`` multiply."""
    from ..io.store import write_file
    from ..probe.experiment import scene_law
    from ..probe.planted import renders_strength
    from ..seeding import derive_seed

    per_scene = {}
    for scene in scenes:
        left, _, truths, _ = _scene(stores, scene)
        law = scene_law(left, truths["left"]["valid"])
        rng = np.random.default_rng(derive_seed("probe-strength", scene))
        strength = renders_strength(left, truths["left"], rng=rng)
        per_scene[scene] = {"law": list(law), "strength": float(strength)}
        log.info("probe planted control, %s: law a %.4g b %.4g, strength %.3f", scene, *law,
                 strength)
    strength = float(np.median([v["strength"] for v in per_scene.values()]))
    record = {
        "strength": strength,
        "factors": [float(f) for f in factors],
        "strengths": {f"{float(f):g}": float(f) * strength for f in factors},
        "scenes": per_scene,
    }
    text = json.dumps(record, indent=2) + "\n"
    write_file(Path(out), lambda tmp: Path(tmp).write_text(text))
    log.info("the renders' strength (median over %d scenes): %.3f", len(per_scene), strength)
    return record


def _condition_data(stores, scene, *, factor, planted, seed_key, shipped=None):
    """The renders of one scene under a condition: the stores' own; for a planted cue the
    planted frames around their seed means; for a seed-mean mitigation trained on what it
    ships (``shipped``: its ``transform`` and ``options``), one image per disjoint group of
    :data:`~stereovar.probe.conditions.SHIPPED_GROUP` renders, each transformed with its own
    group's seed mean (:func:`stereovar.calibration.stacks.shipped_stack`)."""
    from ..probe.experiment import planted_stacks
    from ..seeding import derive_seed

    left, right, truths, sign = _scene(stores, scene)
    if shipped:
        from ..calibration.stacks import shipped_stack
        from ..probe.conditions import SHIPPED_GROUP

        name = shipped["transform"]
        seed = derive_seed("probe-shipped", seed_key, scene, name)
        left, right = (
            shipped_stack(name, stack, view=view, seed=derive_seed(seed, view),
                          options=shipped.get("options"), size=SHIPPED_GROUP)
            for view, stack in (("left", left), ("right", right))
        )
        return left, right, truths, sign, None
    if factor is None:
        return left, right, truths, sign, None
    law = planted["scenes"][scene]["law"]
    strength = float(factor) * float(planted["strength"])
    seed = derive_seed("probe-planted", seed_key, scene, f"{float(factor):g}")
    left, right = planted_stacks(
        left, right, truths["left"], truths["right"], sign=sign, law=law, strength=strength,
        seed=seed,
    )
    return left, right, truths, sign, law


def _read_planted(path):
    return json.loads(Path(path).read_text()) if path else None


def train_job(
    stores: dict,
    outs,
    *,
    scenes,
    condition,
    arch,
    variants,
    fold,
    seeds,
    training: dict,
    factor=None,
    planted=None,
    strata: int = 16,
    planted_seed: int = 0,
    validation_rows: int | None = 64,
    device: str = "cpu",
    shipped: dict | None = None,
) -> list[dict]:
    """Train the networks of ``arch`` for ``condition`` on ``scenes`` (the fold's training
    scenes): for each of ``variants`` (the network, ``main``, and its cue-blind ``twin``) one
    per training seed of ``seeds``, written to ``outs`` in that order (variant-major), each to
    a plateau of validation accuracy on each scene's last seed index, and save each with its
    settings and history (:func:`stereovar.probe.training.save_matcher`). The renders are
    read once. Validation reads a band of ``validation_rows`` rows of each held-out frame; a
    twin trains exactly as many steps as its network (same seed) took to its best check, so
    the two differ only in the twin's shuffled right residual.

    ``stores`` maps ``left_{scene}`` and ``right_{scene}`` to render-store paths and
    ``gt_{scene}`` to the scene's ground-truth store; a planted condition (``factor``) reads
    ``none``'s renders and the planted settings ``planted`` (:func:`planted_job`), a shipped
    one (``shipped``) ``none``'s renders and its transform's options (:func:`_condition_data`)."""
    from ..probe.architectures import architecture
    from ..probe.conditions import TWIN
    from ..probe.experiment import split_validation, training_frames, validation_band
    from ..probe.training import save_matcher

    outs, seeds, variants = list(outs), [int(s) for s in seeds], list(variants)
    if len(outs) != len(seeds) * len(variants):
        raise ValueError(
            f"{len(outs)} network paths for {len(variants)} variants x {len(seeds)} seeds"
        )
    _check_device(device)
    entry = architecture(arch)
    settings = entry.settings(training)
    record = _read_planted(planted)
    data = [
        _condition_data(stores, scene, factor=factor, planted=record, seed_key=planted_seed,
                        shipped=shipped)
        for scene in scenes
    ]
    jobs = [(variant, seed) for variant in variants for seed in seeds]
    best_steps: dict = {}
    metas = []
    frames_of = {}
    for out, (variant, seed) in zip(outs, jobs, strict=True):
        if variant not in frames_of:
            frames_of[variant] = split_validation(
                [
                    training_frames(
                        left, right, truths["left"], sign=sign, twin=variant == TWIN,
                        strata=strata,
                    )
                    for left, right, truths, sign, _ in data
                ]
            )
        frames, validation = frames_of[variant]
        matched = variant == TWIN and seed in best_steps
        if matched:  # the twin trains as long as its network did: no plateau of its own
            own = replace(settings, steps=max(int(best_steps[seed]), 1))
            net, history = entry.train(frames, own, seed=seed, device=device, validation=None)
        else:
            net, history = entry.train(
                frames, settings, seed=seed, device=device,
                validation=validation_band(validation, rows=validation_rows) or None,
            )
            best_steps[seed] = history.get("best_step") or history.get("steps")
        losses = [x for x in history["loss"] if math.isfinite(x)]
        tail = losses[-max(1, len(losses) // 10) :]
        meta = {
            "condition": condition,
            "variant": variant,
            "architecture": arch,
            "factor": factor,
            "fold": int(fold),
            "scenes": list(scenes),
            "frames": len(frames),
            "validation_frames": len(validation),
            "steps": int(history.get("steps", len(history["loss"]))),
            "best_step": history.get("best_step"),
            "matched_steps": matched,
            "cap": int(settings.steps),
            "validation": [list(v) for v in history.get("validation", [])],
            "seconds": history["seconds"],
            "step_seconds": history["step_seconds"],
            "loss_first": float(np.mean(losses[: len(tail)])) if losses else math.nan,
            "loss_last": float(np.mean(tail)) if losses else math.nan,
        }
        save_matcher(out, net, settings=settings, seed=seed, meta=meta)
        best = max((a for _, a in meta["validation"]), default=math.nan)
        log.info(
            "probe %s %s/%s fold %s seed %s: %d frames of %s, %d steps in %.1f s "
            "(%.0f ms/step), best validation accuracy %.4f at step %s, loss %.4f -> %.4f",
            arch,
            condition,
            variant,
            fold,
            seed,
            len(frames),
            ", ".join(scenes),
            meta["steps"],
            history["seconds"],
            1000 * history["step_seconds"],
            best,
            meta["best_step"],
            meta["loss_first"],
            meta["loss_last"],
        )
        metas.append(meta)
    return metas


def _check_device(device: str) -> None:
    """One line when ``probe.device`` names a GPU that PyTorch cannot use."""
    import torch

    from ..errors import ConfigError

    if str(device).startswith("cuda") and not torch.cuda.is_available():
        raise ConfigError(
            f"config key 'probe.device' is {device!r}, but PyTorch sees no CUDA GPU here "
            f"(torch {torch.__version__}); set probe.device: cpu, or install a CUDA build of "
            "PyTorch on a machine with a GPU"
        )


def max_disparity(truths, *, fixed=None, margin: int = 4) -> int:
    """:math:`D`: ``fixed``, or the largest ground-truth disparity plus ``margin``."""
    if fixed is not None:
        return int(fixed)
    top = max(float(np.nanmax(np.where(t["valid"], t["disparity"], np.nan))) for t in truths)
    return int(math.ceil(top)) + int(margin)


def test_job(
    stores: dict,
    networks,
    out,
    *,
    scenes,
    tested,
    arch,
    test: dict,
    factor=None,
    planted=None,
    planted_seed: int = 0,
    max_disparity_fixed=None,
    disparity_margin: int = 4,
    threads: int = 1,
    device: str = "cpu",
    shipped: dict | None = None,
) -> int:
    """Score every network in ``networks`` (the tested condition's, its twins and the
    control's, of one architecture and fold) on every test input of the fold's held-out
    ``scenes`` under ``tested``, a batch of inputs per network; the per-tile sums go to
    ``out`` (:data:`stereovar.probe.metrics.TILE_COLUMNS`). Torch runs ``threads`` threads;
    ``factor``, ``planted`` and ``shipped`` as for :func:`train_job`."""
    import torch

    from ..io.tables import write_tables
    from ..probe.architectures import architecture
    from ..probe.experiment import TestSettings, channel_correlation, scene_law, test_scene
    from ..probe.metrics import TILE_COLUMNS
    from ..probe.training import load_matcher

    torch.set_num_threads(int(threads))
    _check_device(device)
    entry = architecture(arch)
    nets = {}
    for path in networks:
        net, record = load_matcher(path)
        meta = record["meta"]
        key = (meta["condition"], meta.get("variant", "main"), int(record["seed"]))
        nets[key] = net.to(device)
    record = _read_planted(planted)
    data = {
        scene: _condition_data(
            stores, scene, factor=factor, planted=record, seed_key=int(planted_seed) + 1,
            shipped=shipped,
        )
        for scene in scenes
    }
    d_max = max_disparity(
        [truths["left"] for _, _, truths, _, _ in data.values()],
        fixed=max_disparity_fixed,
        margin=disparity_margin,
    )
    settings = TestSettings(**{**test, "max_disparity": d_max})
    rows = []
    for scene, (left, right, truths, sign, law) in data.items():
        truth = truths["left"]
        law = law if law is not None else scene_law(left, truth["valid"])
        regions = PROBE_REGIONS if np.asarray(truth["glass"]).any() else ("all",)
        scene_rows = test_scene(
            nets, entry.predict, left, right, truth, scene=scene, sign=sign, regions=regions,
            law=law, settings=settings, correlation=channel_correlation(left, truth["valid"]),
        )
        rows += [{"tested": tested, "architecture": arch, **r} for r in scene_rows]
        log.info(
            "probe test of %s on %s (%s): %d networks x %d inputs x %d frames, D = %d",
            tested,
            scene,
            arch,
            len(nets),
            len(settings.inputs),
            min(settings.test_frames, left.shape[0]),
            d_max,
        )
    write_tables(rows, list(TILE_COLUMNS), {"csv": out})
    return len(rows)


def _stopped(meta: dict) -> str:
    """How a network's training ended: ``matched`` (a twin: its network's steps to the best
    check), ``collapsed`` (no validation pixel within 1 px at any check: the stop rule saw
    no gain, not a plateau), ``cap`` (the step cap first) or ``plateau`` (its stop rule).

    Examples
    --------
    >>> _stopped({"steps": 150, "cap": 400, "validation": [[50, 0.0], [100, 0.0], [150, 0.0]]})
    'collapsed'
    >>> _stopped({"steps": 150, "cap": 400, "validation": [[50, 0.6], [100, 0.7], [150, 0.7]]})
    'plateau'
    >>> _stopped({"steps": 400, "cap": 400, "validation": [[200, 0.6], [400, 0.7]]})
    'cap'
    """
    if meta.get("matched_steps"):
        return "matched"
    checks = [a for _, a in meta.get("validation") or []]
    if checks and max(checks) == 0:
        return "collapsed"
    return "cap" if "cap" in meta and int(meta["steps"]) >= int(meta["cap"]) else "plateau"


def _each(meta: dict) -> str:
    """One network as ``fold/seed: steps (best step)``, with ``cap`` where the cap stopped it
    and ``collapsed`` where it never predicted a validation pixel within 1 px (:func:`_stopped`).

    Examples
    --------
    >>> _each({"fold": 1, "seed": 2, "steps": 300, "best_step": 250, "cap": 300})
    'f1/s2: 300 (250) cap'
    >>> _each({"fold": 0, "seed": 0, "steps": 250, "best_step": 150, "cap": 600})
    'f0/s0: 250 (150)'
    """
    best = meta.get("best_step")
    out = f"f{meta.get('fold', 0)}/s{meta.get('seed', 0)}: {int(meta['steps'])}"
    out += f" ({best})" if best is not None and not meta.get("matched_steps") else ""
    stopped = _stopped(meta)
    return out + (f" {stopped}" if stopped in ("cap", "collapsed") else "")


def training_rows(networks) -> list[dict]:
    """One row per (architecture, condition, variant): the networks trained, the optimiser
    steps each took to its plateau (mean, min, max), the best step, how each stopped
    (:func:`_stopped`; a twin trains its network's steps, never counted): at the step cap
    before a plateau (``at_cap``), on it (``plateau``) or without ever predicting a
    validation pixel within 1 px (``collapsed``: a learning rate too high, not a plateau),
    each network's steps and best step (``each``),
    the best validation accuracy and the seconds of training, from each network's record."""
    from ..probe.training import load_matcher

    groups: dict = {}
    for path in networks:
        _, record = load_matcher(path)
        meta = record["meta"]
        key = (meta.get("architecture", "mccnn"), meta["condition"], meta.get("variant", "main"))
        groups.setdefault(key, []).append({**meta, "seed": int(record.get("seed", 0))})
    rows = []
    for (arch, condition, variant), metas in groups.items():
        steps = [int(m["steps"]) for m in metas]
        best = [max((a for _, a in m.get("validation") or []), default=math.nan) for m in metas]
        rows.append(
            {
                "architecture": arch,
                "training": condition,
                "variant": variant,
                "networks": len(metas),
                "steps_mean": float(np.mean(steps)),
                "steps_min": min(steps),
                "steps_max": max(steps),
                "best_step_mean": float(np.mean([m.get("best_step") or 0 for m in metas])),
                "at_cap": sum(1 for m in metas if _stopped(m) == "cap"),
                "plateau": sum(1 for m in metas if _stopped(m) == "plateau"),
                "collapsed": sum(1 for m in metas if _stopped(m) == "collapsed"),
                "each": ", ".join(_each(m) for m in sorted(
                    metas, key=lambda m: (int(m.get("fold", 0)), int(m.get("seed", 0))))),
                "validation_accuracy": float(np.nanmean(best)) if np.isfinite(best).any()
                else math.nan,
                "seconds_mean": float(np.mean([m["seconds"] for m in metas])),
            }
        )
    return rows


def probe_table_job(
    tiles, outputs: dict, *, figure, verdict, training_outputs: dict, networks=(),
    planted=None, source="", runs: list | None = None, n_seeds: int | None = None,
) -> list[dict]:
    """The probe table, its training table, its figure and the verdict JSON from every test
    job's tiles and every network's record."""
    import pandas as pd

    from ..io.store import write_file
    from ..io.tables import write_tables
    from ..probe.metrics import INTERVAL_METHOD, probe_rows
    from ..probe.verdict import probe_verdict
    from .common import save_figure

    frames = [pd.read_csv(p) for p in tiles]
    table = pd.concat(frames, ignore_index=True)
    record = _read_planted(planted)
    strengths = (
        {name: float(v) for name, v in record["strengths"].items()} if record else None
    )
    rows = probe_rows(table, strengths=strengths)
    columns = list(dict.fromkeys(k for r in rows for k in r))
    write_tables(
        rows,
        columns,
        outputs,
        caption=(
            "The learned probe, per architecture: accuracy (|d - d_GT| < 1 px), end-point "
            "error, the drop from the normal input, the difference in differences (DiD) of that "
            "drop against the condition's cue-blind twin (did) and against the sensor_only "
            "network (did_sensor) on the same inputs, the share of predictions at d = 0, and "
            f"for the cue conflict the share of pixels at d + k; {INTERVAL_METHOD}"
        ),
        constants={"source": source} if source else None,
    )
    trained = training_rows(networks)
    write_tables(
        trained,
        list(trained[0]) if trained else [],
        training_outputs,
        caption=(
            "Training of the probe's networks to a plateau of validation accuracy on held-out "
            "frames: steps taken, best step, best validation accuracy and seconds, per "
            "architecture, condition and variant (mean over folds and training seeds)"
        ),
        constants={"source": source} if source else None,
    )
    result = probe_verdict(rows)
    result["source"] = source
    result["runs"] = list(runs or [])
    result["training"] = trained
    result["paragraph"] += _caveats(trained, n_seeds)
    if n_seeds:
        result["aligned_share_kept"] = 1.0 / (int(n_seeds) - 1)
    if record:
        result["renders_strength"] = record["strength"]
    text = json.dumps(_clean(result), indent=2) + "\n"
    write_file(Path(verdict), lambda tmp: Path(tmp).write_text(text))
    from ..figures.probe import probe_figure

    save_figure(probe_figure(rows), figure)
    log.info("%s", result["paragraph"])
    return rows


def _caveats(trained: list[dict], n_seeds) -> str:
    """What the verdict rests on beyond its intervals: networks stopped at the step cap
    before a plateau, and the share of the aligned noise the shuffled inputs keep."""
    out = ""
    mains = [r for r in trained if r["variant"] == "main"]
    capped = sum(int(r["at_cap"]) for r in mains)
    if capped:
        total = sum(int(r["networks"]) for r in mains)
        named = "; ".join(
            f"{r['architecture']} {r['training']} {int(r['at_cap'])} of {int(r['networks'])}"
            for r in mains if int(r["at_cap"]))
        out += (
            f" {capped} of the {total} networks stopped at the step cap before a plateau of "
            f"validation accuracy ({named}; results/tables/probe_training.*): raise "
            "probe.training.steps and probe.costvolume.steps to train them to one."
        )
    collapsed = [r for r in mains if int(r.get("collapsed", 0))]
    if collapsed:
        named = "; ".join(f"{r['architecture']} {r['training']} {int(r['collapsed'])} of "
                          f"{int(r['networks'])}" for r in collapsed)
        out += (
            f" {sum(int(r['collapsed']) for r in collapsed)} networks never predicted a "
            f"validation pixel within 1 px ({named}): they collapsed rather than converged; "
            "lower probe.training.learning_rate or probe.costvolume.learning_rate."
        )
    if n_seeds:
        out += (
            f" The shuffled inputs' reference mean of the other {int(n_seeds) - 1} renders keeps "
            f"1/{int(n_seeds) - 1} = {100 / (int(n_seeds) - 1):.0f}% of the aligned noise "
            "variance, so a reliance is measured at about "
            f"{100 * (int(n_seeds) - 2) / (int(n_seeds) - 1):.0f}% of its size."
        )
    return out


def _clean(value):
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_clean(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
