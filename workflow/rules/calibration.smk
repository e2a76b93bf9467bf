# The calibration (stereovar.calibration): synthetic frames made from each scene's own seed
# means, disparity and N, whose answer is known, passed through every transform, statistic
# and verdict rule of the run; then results/tables/calibration.* and its figure. Nothing is
# rendered.


rule calibration_scene:
    wildcard_constraints:
        renderer=SOURCE_NAMES,
    input:
        unpack(calibration_scene_inputs),
    output:
        layout.calibration_rows("{renderer}", "{estimator}", "{scene}", "{spp}"),
    params:
        transforms=CALIBRATION_TRANSFORMS,
        options=calibration_options(),
        calibration=config["calibration"],
        analysis=config["analysis"],
        controls=config["controls"],
        intervention=config["intervention"],
    log:
        "logs/{renderer}/{estimator}/calibration/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/{estimator}/calibration/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **calibration_resources(),
    conda:
        ENV
    script:
        "../scripts/calibration_scene.py"


rule calibration_table:
    input:
        calibration_table_inputs(),
    output:
        csv=CALIBRATION_TABLES[0],
        md=CALIBRATION_TABLES[1],
        nulls=CALIBRATION_NULLS,
        figure=report(
            CALIBRATION_FIGURE,
            caption="../report/calibration.rst",
            category="Figures",
            labels={"figure": "calibration"},
        ),
    log:
        f"logs/{MITIGATION_SOURCE}/tables/calibration.log",
    benchmark:
        f"benchmarks/{MITIGATION_SOURCE}/tables/calibration.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/calibration_table.py"


rule calibration:
    input:
        calibration_targets(),
    localrule: True
