# Configuration validation, wildcard constraints, input functions and target lists.
from pathlib import Path

import yaml
from snakemake.utils import validate

from stereovar.config import validate_config_or_exit

CONFIG_SCHEMA = "../schemas/config.schema.yaml"

config.update(validate_config_or_exit(config, workflow.source_path(CONFIG_SCHEMA)))


validate(config, CONFIG_SCHEMA, set_default=True)


ENV = "../../envs/stereovar.yaml"
SCENES = list(config["scenes"])
GENERATED_SCENE = r"scene_\d{3}"


wildcard_constraints:
    scene=r"[A-Za-z0-9_-]+",
    view="left|right",


def scene_spec_path(scene):
    """Path of a scene's spec file."""
    return f"scenes/{scene}.yaml"


def scene_inputs(wildcards):
    """The spec of a scene and, for XML scenes, the Mitsuba file it points at."""
    spec = Path(scene_spec_path(wildcards.scene))
    inputs = {"spec": str(spec)}
    if spec.is_file():
        data = yaml.safe_load(spec.read_text()) or {}
        if isinstance(data, dict) and isinstance(data.get("mitsuba_xml"), str):
            inputs["xml"] = str(spec.parent / data["mitsuba_xml"])
    return inputs


def rig_params():
    """Resolution and rig settings shared by every job that builds the stereo rig."""
    return {
        "width": config["resolution"]["width"],
        "height": config["resolution"]["height"],
        "baseline_m": config["rig"]["baseline_m"],
        "convention": config["rig"]["convention"],
        "variant": config["render"]["variant"],
    }


def render_params():
    """Integrator, filter and sampler settings of every render."""
    r = config["render"]
    return {
        "variant": r["variant"],
        "integrator": r["integrator"],
        "max_depth": r["max_depth"],
        "rfilter": r["rfilter"],
        "sampler": r["sampler"],
    }


def check_scene_specs():
    """Stop before any job when a listed scene has no spec and cannot be generated."""
    import re

    missing = [
        s
        for s in SCENES
        if not Path(scene_spec_path(s)).is_file() and not re.fullmatch(GENERATED_SCENE, s)
    ]
    if missing:
        raise WorkflowError(
            f"config key 'scenes': no spec file for {', '.join(missing)} "
            f"(expected scenes/<name>.yaml); add the spec or remove the name from 'scenes'"
        )


check_scene_specs()


def all_targets():
    """Everything `snakemake all` builds."""
    return [
        *expand("results/ground_truth/{scene}.zarr", scene=SCENES),
        *expand("results/figures/previews/{scene}.png", scene=SCENES),
        *expand("results/tables/scenes.{ext}", ext=["csv", "md", "tex"]),
    ]
