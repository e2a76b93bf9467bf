"""What the workflow's rule files ask of the library while Snakemake reads them: the logic of
their input functions, params and cluster requests, as plain functions of the config's values
(no Snakemake object), so each has unit tests. ``workflow/rules/inputs/<feature>.smk`` holds
the thin input functions that pass the run's values in.

``resources`` builds each job's cluster requests (memory, runtime, GPUs) from its size;
``scenes`` finds the listed scenes without a spec and a spec's input files; ``mitigations``
decides what a mitigated or calibrated image reads and costs; ``run`` repeats a run's
config options for the rebuild commands and picks the results page's figures and tables.
"""
