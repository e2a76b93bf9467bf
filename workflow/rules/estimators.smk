# The moments estimator against Eq. 1 over many seeds (target `estimators`, not in `all`):
# per scene, the two fields compared and every statistic by both estimators; the tables
# and the figure over every scene.


rule estimator_check:
    input:
        unpack(estimator_check_inputs),
    output:
        fields=layout.estimator_check_fields("{renderer}", "{scene}", "{spp}"),
        rows=layout.estimator_check_rows("{renderer}", "{scene}", "{spp}"),
    params:
        analysis=config["analysis"],
        controls=config["controls"],
    log:
        "logs/{renderer}/estimators/{scene}/spp{spp}.log",
    benchmark:
        "benchmarks/{renderer}/estimators/{scene}/spp{spp}.tsv"
    threads: 1
    resources:
        **analysis_resources(images=24, n_reads=2 * (VALIDATION_N_SEEDS + 1)),
    conda:
        ENV
    script:
        "../scripts/estimator_check.py"


rule estimator_tables:
    input:
        fields=[
            layout.estimator_check_fields(get_renderer(), s, VALIDATION_SPP) for s in SCENES
        ],
        rows=[
            layout.estimator_check_rows(get_renderer(), s, VALIDATION_SPP) for s in SCENES
        ],
    output:
        **table_outputs(
            layout.estimator_tables(),
            caption="../report/estimators.rst",
            category="Estimators",
            labels={"table": "seeds against moments: every statistic"},
        ),
        **table_outputs(
            layout.estimator_field_tables(),
            prefix="fields_",
            caption="../report/estimator_fields.rst",
            category="Estimators",
            labels={"table": "seeds against moments: the fields"},
        ),
        figure=report(
            layout.estimator_figure(),
            caption="../report/fig_estimators.rst",
            category="Estimators",
            labels={"figure": "seeds against moments"},
        ),
    log:
        "logs/tables/estimators.log",
    benchmark:
        "benchmarks/tables/estimators.tsv"
    localrule: True
    conda:
        ENV
    script:
        "../scripts/estimator_tables.py"


rule estimators:
    input:
        rules.estimator_tables.output,
    localrule: True
