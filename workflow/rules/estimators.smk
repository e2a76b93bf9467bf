# The moments estimator against Eq. 1 over many seeds (target `estimators`, not in `all`):
# per scene, the two fields compared and every statistic by both estimators; the tables
# and the figure over every scene.


rule estimator_check:
    input:
        unpack(estimator_check_inputs),
    output:
        fields="results/{renderer}/estimators/{scene}/spp{spp}_fields.csv",
        rows="results/{renderer}/estimators/{scene}/spp{spp}.csv",
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
        fields=expand(
            "results/{renderer}/estimators/{scene}/spp{spp}_fields.csv",
            renderer=get_renderer(),
            scene=SCENES,
            spp=VALIDATION_SPP,
        ),
        rows=expand(
            "results/{renderer}/estimators/{scene}/spp{spp}.csv",
            renderer=get_renderer(),
            scene=SCENES,
            spp=VALIDATION_SPP,
        ),
    output:
        csv="results/tables/estimators.csv",
        md="results/tables/estimators.md",
        tex="results/tables/estimators.tex",
        html=report(
            "results/tables/estimators.html",
            caption="../report/estimators.rst",
            category="Estimators",
            labels={"table": "seeds against moments: every statistic"},
        ),
        fields_csv="results/tables/estimator_fields.csv",
        fields_md="results/tables/estimator_fields.md",
        fields_tex="results/tables/estimator_fields.tex",
        fields_html=report(
            "results/tables/estimator_fields.html",
            caption="../report/estimator_fields.rst",
            category="Estimators",
            labels={"table": "seeds against moments: the fields"},
        ),
        figure=report(
            "results/figures/estimators.png",
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
