"""Pages: self-contained HTML pages a person opens, readable without Snakemake's report app.

``templates``
    The Jinja2 environment of every page (``stereovar/pages/templates/``, autoescaping on):
    ``base.html.j2`` (the document and the shared stylesheet) that each page extends, and
    ``macros.html.j2`` (figure, table, verdict badge, links).
``html``
    The building blocks for a page that passes ready fragments (document, table, figure, all
    rendered by the templates), an image as a PNG data URI, a relative link.
``captions``
    The report's captions (``workflow/report/*.rst``) rendered with the run's config, and as
    HTML by docutils with MathML math.
``names``
    What people read for the claims: names, paper sections by name, controls in words.
``results``
    The main run's page, ``results/index.html`` (``results.html.j2``): a one-line conclusion,
    the Monte Carlo-specific :math:`\\rho` with its interval beside its matched null and the
    controls, the claims table, the figures with captions, the mitigations, the learned probe
    and the generator profiles when they have run, and links to the tables and the report.

The audit's verdict page (:mod:`stereovar.audit.page`) is built from the same templates.
Importing this package imports none of its modules.
"""
