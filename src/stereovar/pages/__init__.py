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
``numbers``
    Numbers as the pages show them: significant digits, a value with its 95% interval (also
    the templates' ``significant`` filter).
``headline``
    The results page's headline: :math:`\\rho` after the warp and the Monte Carlo-specific
    :math:`\\rho` beside its matched null, each with the interval the page shows it with.
``controls``
    The results page's table by region: the headline and its controls with their intervals,
    marked where the claims call a number explained by a control.
``conclusion``
    The results page's one-line conclusion: a word for the verdict and its sentence.
``claims_table``
    The results page's claims table: each claim by name, our number with its interval, the
    control in words, the verdict's badge.
``mitigation_table``
    The results page's compact mitigation table.
``results``
    The main run's page, ``results/index.html`` (``results.html.j2``): a one-line conclusion,
    the Monte Carlo-specific :math:`\\rho` with its interval beside its matched null and the
    controls, the claims table, the figures with captions, the mitigations, the learned probe
    and the generator profiles when they have run, and links to the tables and the report;
    its sections put together from the modules above.

The audit's verdict page (:mod:`stereovar.audit.page`) is built from the same templates.
Importing this package imports none of its modules.
"""
