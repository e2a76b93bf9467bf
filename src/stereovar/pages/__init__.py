"""Pages: self-contained HTML pages a person opens, readable without Snakemake's report app.

``html``
    The building blocks every page shares: the document with its stylesheet, a table, a
    figure (by relative path or embedded as a PNG data URI), a relative link.
``captions``
    The report's captions (``workflow/report/*.rst``) rendered with the run's config, as
    page text.
``results``
    The main run's page, ``results/index.html``: the headline :math:`\\rho` with its
    interval and controls, the claims table, the figures with captions, the mitigations and
    the learned probe when they have run, and links to the tables and the report.

The audit's verdict page (:mod:`stereovar.audit.page`) is built from the same blocks.
Importing this package imports none of its modules.
"""
