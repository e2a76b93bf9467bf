"""A run's own options and pages: the ``--configfile`` and ``--config`` options a rebuild
command repeats, and the figures and tables of ``all`` that the results page shows.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import yaml


def snakemake_arguments(configfiles, overrides: dict | None) -> str:
    """A run's ``--configfile`` files and ``--config`` overrides as one shell fragment (the
    rebuild commands printed for a damaged store repeat them); empty without either.

    Examples
    --------
    >>> snakemake_arguments(["my run.yaml"], {"render": {"spp": 4}})
    "--configfile 'my run.yaml' --config 'render={spp: 4}'"
    """
    parts = [f"--configfile {shlex.quote(str(f))}" for f in configfiles]
    if overrides:
        entries = []
        for key, value in overrides.items():
            text = yaml.safe_dump(value, default_flow_style=True, width=10**6).strip()
            entries.append(shlex.quote(f"{key}={text.removesuffix('...').strip()}"))
        parts.append("--config " + " ".join(entries))
    return " ".join(parts)


def page_results(targets, own, table_formats) -> tuple[list, list]:
    """``(figures, tables)`` of the results page: of ``targets`` (those of ``all``), less
    ``own`` (the page and the figures its sections show themselves), every PNG in a
    ``figures`` folder and every file in a ``tables`` folder of one of ``table_formats``.

    Examples
    --------
    >>> page_results(["r/figures/a.png", "r/tables/t.csv", "r/tables/t.json", "r/index.html"],
    ...              {"r/index.html"}, ("csv",))
    (['r/figures/a.png'], ['r/tables/t.csv'])
    """
    paths = [Path(p) for p in targets if p not in own]
    figures = [str(p) for p in paths if p.parent.name == "figures" and p.suffix == ".png"]
    tables = [
        str(p) for p in paths if p.parent.name == "tables" and p.suffix[1:] in table_formats
    ]
    return figures, tables
