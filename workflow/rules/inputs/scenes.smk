# Scene specs, read by scenes.smk and by the rules that build a scene: a spec's inputs
# (with an XML scene's files), and the check, made while the workflow is read, that every
# listed scene has a spec or can be generated (stereovar.workflow_inputs.scenes).
from stereovar.workflow_inputs import scenes as scene_specs


def scene_inputs(wildcards):
    """The spec of the wildcards' scene and, for XML scenes, the Mitsuba file it points at and
    every file that reads (:func:`stereovar.workflow_inputs.scenes.scene_inputs`)."""
    return scene_specs.scene_inputs(wildcards.scene, xml_references)


TO_GENERATE, UNKNOWN_SCENES = scene_specs.missing_scene_specs(SCENES, audit=bool(AUDIT))
if UNKNOWN_SCENES:
    raise SystemExit(
        f"stereovar: config key 'scenes': no spec file for {', '.join(UNKNOWN_SCENES)} "
        "(expected scenes/<name>.yaml); add the spec or remove the name from 'scenes'"
    )
# Every existing spec, with the XML file it points at and the files that reads, is checked
# here, before any job starts: a job that found the problem would first have its outputs
# deleted by Snakemake.
with exit_with_one_line():
    check_scene_specs(
        scene_specs.scene_spec_path(s) for s in SCENES if s not in TO_GENERATE and not AUDIT
    )
# The generator rule only applies to specs that are missing (a pattern matching nothing
# otherwise), so it never overwrites a committed or edited spec.
GENERATE_PATTERN = "|".join(re.escape(s) for s in TO_GENERATE) or r"(?!x)x"
