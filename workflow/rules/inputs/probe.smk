# Inputs and targets of the learned probe (probe.smk, probe_model.smk).


# The learned probe (stereovar.probe): per architecture, one network per training condition,
# variant (the network and its cue-blind twin), fold and training seed; one test job per
# condition, architecture and fold scores the condition's networks, their twins and the
# control's on the fold's held-out scenes under the condition. A planted condition reads the
# renders of `none` with a planted cue of known strength (probe/planted.json); a shipped one
# (a judged seed-mean mitigation) reads them too and builds what the mitigation ships.
from stereovar.probe.conditions import CONTROL as PROBE_CONTROL
from stereovar.probe.conditions import MAIN as PROBE_MAIN
from stereovar.probe.architectures import architecture
from stereovar.probe.conditions import check_probe, probe_conditions

PROBE = config["probe"]
PROBE_WANTED = not AUDIT or bool(AUDIT.get("probe"))
with exit_with_one_line():
    PROBE_CONDITIONS = (
        {c.name: c for c in probe_conditions(config)} if PROBE_WANTED else {}
    )
PROBE_ARCHS = list(dict.fromkeys(PROBE["architectures"]))
PROBE_FOLDS = int(PROBE["folds"])
PROBE_SEEDS = list(range(int(PROBE["train_seeds"])))
PROBE_SOURCE = get_renderer()
PROBE_TABLES = layout.probe_tables(PROBE_SOURCE)
PROBE_TRAINING_TABLES = layout.probe_training_tables(PROBE_SOURCE)
PROBE_FIGURE = layout.probe_figure(PROBE_SOURCE)
PROBE_VERDICT = layout.probe_verdict(PROBE_SOURCE)
PROBE_PLANTED = layout.probe_planted(PROBE_SOURCE)
PROBE_ANY_PLANTED = any(c.planted for c in PROBE_CONDITIONS.values())
PROBE_TWINNED = [name for name, c in PROBE_CONDITIONS.items() if c.twin]
# the control trains without a twin (judged, it trains as sensor_only_shipped); the
# condition keeps the general case of a twinned control
PROBE_CONTROL_UNTWINNED = PROBE_CONTROL in PROBE_CONDITIONS and PROBE_CONTROL not in PROBE_TWINNED
# wildcard patterns: the conditions, those with a twin, the architectures
PROBE_CONDITION_PATTERN = "|".join(map(re.escape, PROBE_CONDITIONS)) or "none"
PROBE_TWINNED_PATTERN = "|".join(map(re.escape, PROBE_TWINNED)) or "none"
PROBE_ARCH_PATTERN = "|".join(PROBE_ARCHS) or "mccnn"


def probe_folds():
    """(training scenes, held-out scenes) of every fold; a config error when the scenes
    cannot fill ``probe.folds`` folds."""
    from stereovar.probe.folds import fold_scenes
    from stereovar.errors import ConfigError

    try:
        return fold_scenes(SCENES, PROBE_FOLDS)
    except ValueError as err:
        raise ConfigError(f"config key 'probe.folds': {err}") from None


def probe_stores(key, spp, scenes):
    """Render stores of each view and the ground truth of ``scenes`` under source key ``key``
    at ``spp``, named ``left_{scene}``, ``right_{scene}`` and ``gt_{scene}``."""
    stores = {}
    for scene in scenes:
        views = seed_stores(run_config(key), scene, spp)
        stores.update({f"{view}_{scene}": views[view] for view in VIEWS})
        stores[f"gt_{scene}"] = ground_truth_store(key, scene)
    return stores


def probe_condition_stores(name, scenes):
    """The stores condition ``name`` reads for ``scenes`` (a planted condition: ``none``'s
    renders and the planted settings, ``planted``)."""
    condition = PROBE_CONDITIONS[name]
    run = condition.run
    stores = probe_stores(layout.source_key(run.source, run.transform), run.spp, scenes)
    if condition.planted:
        stores["planted"] = PROBE_PLANTED
    return stores


def probe_shipped(condition):
    """A shipped condition's transform and its options as the transform rule passes them
    (its images are built in the probe's jobs from ``none``'s renders), else None."""
    name = PROBE_CONDITIONS[condition].shipped
    if name is None:
        return None
    options = mitigation_inputs.transform_options(name, config["controls"]["sensor"])
    return {"transform": name, "options": options}


def probe_checked():
    """The probe's settings that fail before any job (too few renders per view, a GPU that
    PyTorch cannot use), checked when the plan first holds a probe job: one line and exit."""
    with exit_with_one_line():
        check_probe(config, N_SEEDS)


def probe_planted_inputs(wildcards):
    """`none`'s renders of every scene, whose strength and camera laws set the planted cue."""
    probe_checked()
    return probe_condition_stores("none", SCENES)


def probe_train_inputs(wildcards):
    """The training scenes of the wildcards' fold under its condition."""
    probe_checked()
    return probe_condition_stores(wildcards.condition, probe_folds()[int(wildcards.fold)][0])


def probe_networks(condition, arch, fold):
    """The networks one test job scores: the condition's, its twins' and the control's."""
    variants = [(condition, v) for v in PROBE_CONDITIONS[condition].variants]
    if condition != PROBE_CONTROL:
        variants.append((PROBE_CONTROL, PROBE_MAIN))
    return [
        layout.probe_network(PROBE_SOURCE, c, arch, v, fold, j)
        for c, v in variants
        for j in PROBE_SEEDS
    ]


def probe_test_inputs(wildcards):
    """The held-out scenes of the wildcards' fold under its condition, and the networks."""
    fold = int(wildcards.fold)
    return {
        **probe_condition_stores(wildcards.condition, probe_folds()[fold][1]),
        "networks": probe_networks(wildcards.condition, wildcards.arch, fold),
    }


def probe_pairs():
    """(condition, architecture) of every network family: an architecture's own planted
    series (``probe.planted_series``) is trained by that architecture only."""
    return [(c, a) for c in PROBE_CONDITIONS for a in PROBE_ARCHS
            if PROBE_CONDITIONS[c].trains(a)]


def probe_tile_files():
    """Every test job's tile table."""
    return [
        layout.probe_tiles(PROBE_SOURCE, c, a, f)
        for c, a in probe_pairs()
        for f in range(PROBE_FOLDS)
    ]


def probe_network_files():
    """Every network of the probe."""
    return sorted(
        {
            path
            for c, a in probe_pairs()
            for f in range(PROBE_FOLDS)
            for path in probe_networks(c, a, f)
        }
    )


def probe_table_inputs(wildcards):
    """Every tile table and network, and the planted settings where a planted cue runs."""
    inputs = {"tiles": probe_tile_files(), "networks": probe_network_files()}
    if PROBE_ANY_PLANTED:
        inputs["planted"] = PROBE_PLANTED
    return inputs


def probe_model_stores(wildcards=None):
    """Every frame's render stores of each view and its ground truth (``left_{scene}``,
    ``right_{scene}``, ``gt_{scene}``): the audit's imported frames, or the run's scenes."""
    return probe_stores(get_renderer(), MAIN_SPP, SCENES)


def probe_targets():
    """`snakemake probe`: the probe table, figure and verdict (nothing for an audit without
    ``audit.probe: true``)."""
    if not PROBE_CONDITIONS:
        return []
    return [*PROBE_TABLES, *PROBE_TRAINING_TABLES, PROBE_FIGURE, PROBE_VERDICT]
