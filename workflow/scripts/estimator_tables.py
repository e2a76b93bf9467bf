"""Snakemake adapter: the estimator tables and figure over every scene."""

from stereovar.jobs.common import run_job
from stereovar.jobs.estimators import estimator_tables_job

out = snakemake.output
run_job(
    snakemake.log[0],
    estimator_tables_job,
    fields=list(snakemake.input.fields),
    rows=list(snakemake.input.rows),
    outputs={"csv": out.csv, "md": out.md, "tex": out.tex, "html": out.html},
    fields_outputs={
        "csv": out.fields_csv,
        "md": out.fields_md,
        "tex": out.fields_tex,
        "html": out.fields_html,
    },
    figure=out.figure,
)
