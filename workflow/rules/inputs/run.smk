# The run around the jobs: the rebuild command's arguments, a killed run's lock, the checks
# of `onstart` (preflight) and the summary of `onsuccess` (Snakefile), and the --report warning.
from stereovar.workflow_inputs import run as run_inputs


def snakemake_arguments():
    """This run's ``--configfile`` and ``--config`` options, as a shell fragment: the
    rebuild commands printed for a damaged store repeat them
    (:func:`stereovar.workflow_inputs.run.snakemake_arguments`)."""
    return run_inputs.snakemake_arguments(
        workflow.overwrite_configfiles, workflow.config_settings.config
    )


# Repeated by the rebuild command of any damaged-store message of this run's jobs.
set_rerun_arguments(snakemake_arguments())

# A run killed on this host leaves its lock behind; the same command then resumes instead
# of asking for --unlock (stereovar.preflight.stale_lock: only a lock whose run is gone).
if workflow.is_main_process and clear_stale_lock(STATE_DIR):
    print("stereovar: removed the lock of an earlier run that was killed", file=sys.stderr)


RENDERER_RULES = {"render", "ground_truth", "preview"}


def preflight():
    """Checks made in ``onstart``, after the DAG is known and before any job (and so before
    Snakemake deletes any output): the back end that this machine's jobs would use is
    available, and the renders that the tables pool come from one back end
    (:func:`stereovar.preflight.check_backends`). A cluster run's jobs resolve the back end
    on their own nodes; their renders are checked by the jobs that pool them."""
    from stereovar.renderers import get_renderer as renderer_named

    mark_run(STATE_DIR)
    jobs = list(workflow.dag.needrun_jobs())
    outputs = {str(f) for job in jobs for f in job.output}
    rules = {job.rule.name for job in jobs}
    with exit_with_one_line():
        for renderer in [get_renderer()] if AUDIT else RENDERER_RUNS:
            kept = stored_backends(p for p in render_stores(renderer) if p not in outputs)
            renders = {
                job.rule.name
                for job in jobs
                if job.wildcards.get("renderer", renderer) == renderer
            }
            planned = None
            if workflow.local_exec and renders & RENDERER_RULES:
                planned = renderer_named(renderer).backend(config["render"]["variant"])
            check_backends(
                kept,
                planned if "render" in renders else None,
                allow_mixed=config["render"]["allow_mixed_backends"],
            )
    # an audit that imports a frame again or rebuilds its verdict: the old verdict is set
    # aside (results/audit/<name>/previous/) until the new one is written
    if AUDIT and rules & {"audit_import", "audit_verdict"}:
        set_aside_verdict(AUDIT["name"])


def warn_if_report_is_stale(summary=layout.summary_json()):
    """With ``--report``: warn when the stored results were made with another config (the
    report shows whatever tables exist, whichever config made them)."""
    if not any(a == "--report" or a.startswith("--report=") for a in sys.argv):
        return
    path = Path(summary)
    stored = json.loads(path.read_text()).get("config_digest") if path.is_file() else None
    if stored != config_digest(dict(config)):
        why = "there is none yet" if stored is None else "it was made with another config"
        print(
            f"stereovar: warning: {summary} does not match this config ({why}); the report "
            "would show older tables: run `snakemake -j2 all` with the same options first",
            file=sys.stderr,
        )


warn_if_report_is_stale()


def print_summary():
    """At the end of a successful run: the claims table (Markdown), or an audit's verdict
    summary lines, when they exist."""
    if AUDIT:
        summary = Path(audit_paths(AUDIT["name"])["summary"])
        if summary.exists():
            print("\n" + "\n".join(json.loads(summary.read_text())["summary"]))
        return
    table = Path(layout.claims_tables()[layout.TABLE_FORMATS.index("md")])
    if table.exists():
        print(f"\n{table}:\n\n{table.read_text()}")
