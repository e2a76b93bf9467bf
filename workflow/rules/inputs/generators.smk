# Inputs, params and targets of the generator profiles (generators.smk).


# Generator profiles (stereovar.generators; rules in generators.smk): each profile as rendered
# at the budget (generators.spp), its render stores and the matched null's inputs.
from stereovar.errors import ConfigError
from stereovar.generators import PAPER, PROFILES, generator_profiles
from stereovar.jobs.generators import profile_matched_transform, profile_output_chain
from stereovar.renderers.cycles.settings import cycles_options
from stereovar.transforms import CHAIN

GENERATORS = config["generators"]
GENERATOR_SPP = int(GENERATORS["spp"])
GENERATOR_SCENES = list(GENERATORS["scenes"] or SCENES[:2])
# an audit renders nothing: its profiles are never planned
GENERATOR_ROWS = {}
if not AUDIT:
    with exit_with_one_line():
        GENERATOR_ROWS = {p.name: p for p in generator_profiles(config)}
        _outside = [s for s in GENERATOR_SCENES if s not in SCENES]
        if _outside:
            raise ConfigError(
                f"config key 'generators.scenes': {', '.join(_outside)} not in 'scenes'; "
                "list only scenes of the run"
            )


def generator_calibration_inputs(wildcards):
    """The variance store the profile's matched null is drawn like and the ground truth: the
    profile's own, or for a profile whose denoiser runs the paper row's (the raw renders'
    noise level, which the null then passes through OIDN with each view's albedo and normal
    from Mitsuba's auxiliary pass of the same scene)."""
    profile = GENERATOR_ROWS[wildcards.profile]
    matched = profile_matched_transform(profile.cycles)
    drawn_like = PAPER if matched == "denoise" else profile.name
    inputs = {
        "variance": layout.variance_store(
            layout.generator_source(drawn_like), "seeds", wildcards.scene, wildcards.spp
        ),
        "ground_truth": layout.traced_ground_truth(wildcards.scene),
    }
    if matched == "denoise":
        for view in VIEWS:
            inputs[f"aux_{view}"] = layout.aux_store("mitsuba", wildcards.scene, view)
    if profile_output_chain(profile.name, profile.cycles):
        # the profile's own renders, measured as it ships them
        stores = seed_stores(
            run_config(layout.generator_source(profile.name)), wildcards.scene, wildcards.spp
        )
        for view in VIEWS:
            inputs[f"output_{view}"] = stores[view]
    return inputs


def generator_calibration_transforms(profile):
    """The transforms a profile's matched nulls pass through: ``none``, its matched
    transform and the chain of what it ships (:func:`profile_output_chain`)."""
    chain = profile_output_chain(profile.name, profile.cycles)
    names = ["none", profile_matched_transform(profile.cycles), *([chain] if chain else [])]
    return list(dict.fromkeys(names))


def generator_outputs(profile):
    """The profile's shipped chain to the writer its renders pass through."""
    chain = profile_output_chain(profile.name, profile.cycles)
    return {chain: chain.split(CHAIN)[-1]} if chain else {}


def generator_table_params():
    """Per profile: the profile as rendered and its per-scene files."""
    runs = []
    for name, p in GENERATOR_ROWS.items():
        source = layout.generator_source(name)
        runs.append(
            {
                "profile": name,
                "spp": p.spp,
                "generator_spp": round(p.spp / p.scale),
                "scale": p.scale,
                "cycles": p.cycles,
                "calibration_transform": profile_matched_transform(p.cycles),
                "output_transform": profile_output_chain(name, p.cycles),
                "correlation": [
                    layout.correlation_rows(source, "seeds", s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
                "scene_rows": [
                    layout.mitigation_rows(source, "seeds", s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
                "calibration": [
                    layout.generator_calibration_rows(name, s, GENERATOR_SPP)
                    for s in GENERATOR_SCENES
                ],
            }
        )
    return runs


def generator_targets():
    """`snakemake generators`: the generator table and its figure."""
    return [*layout.generator_tables(), layout.generator_figure()]
