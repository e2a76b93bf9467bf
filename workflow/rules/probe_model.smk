# The user's own stereo network on the counterfactual inputs (stereovar.probe.user_model):
# `stereovar probe --model package.module:factory --weights FILE` builds the frames'
# stores with `probe_model_frames` and runs the model itself; an audit with
# `audit.probe_model: {factory, weights}` gets results/audit/{name}/tables/probe_model.*.

from stereovar.jobs.probe_model import frames_manifest

PROBE_MODEL_SOURCE = get_renderer()  # the renderer, or the audit's source
PROBE_MODEL = (AUDIT or {}).get("probe_model")


# The frames `stereovar probe` runs the model on, made if missing, and listed.
rule probe_model_frames:
    input:
        unpack(probe_model_stores),
    output:
        frames_manifest(PROBE_MODEL_SOURCE),
    log:
        f"logs/{PROBE_MODEL_SOURCE}/probe_model/frames.log",
    params:
        scenes=SCENES,
    localrule: True
    conda:
        ENV
    script:
        "../scripts/probe_model_frames.py"


if PROBE_MODEL:

    rule probe_model:
        input:
            unpack(probe_model_stores),
            weights=PROBE_MODEL["weights"],
        output:
            csv=layout.probe_model_tables(PROBE_MODEL_SOURCE)[0],
            md=layout.probe_model_tables(PROBE_MODEL_SOURCE)[1],
            tex=layout.probe_model_tables(PROBE_MODEL_SOURCE)[2],
            html=layout.probe_model_tables(PROBE_MODEL_SOURCE)[3],
        params:
            scenes=SCENES,
            factory=PROBE_MODEL["factory"],
            device=PROBE_MODEL.get("device", "cpu"),
            source=PROBE_MODEL_SOURCE,
        log:
            f"logs/{PROBE_MODEL_SOURCE}/tables/probe_model.log",
        benchmark:
            f"benchmarks/{PROBE_MODEL_SOURCE}/tables/probe_model.tsv"
        threads: 2
        conda:
            ENV
        script:
            "../scripts/probe_model.py"
