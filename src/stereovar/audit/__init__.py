"""Audits of renders made elsewhere: import, sign check, verdict and export.

``layout`` finds an audit's files from path templates; ``importer`` writes them into the
render and ground-truth store contracts (with provenance and SHA-256s, re-importing only
what changed), from its parts: ``settings`` checks and digests the ``audit:`` settings,
``hashing`` hashes every file as it is decoded and fingerprints a frame's files,
``decoding`` decodes a frame's renders and ground truth, and ``records`` holds what an
import finds and records; ``ground_truth`` builds the imported ground truth; ``sign``
settles the disparity convention photometrically and ``offset`` finds a disparity off by a
pixel or more; ``verdict`` decides whether the data carry the cue, ``seeding`` whether the
two views share their random streams, ``flags`` flags the verdict's own numbers and
``decision`` words the page's opening (a traffic light, how sure, what to do); ``strongest``
finds the frames and tiles where the cue is strongest, ``page`` lays the verdict out as one
page (with ``plain`` saying what its numbers mean in plain words) and
``summary_schema`` checks its ``summary.json`` against the shipped schema; ``run`` makes an
audit a workflow run (its discovery, config and targets, which ``stereovar audit`` drives);
``export`` writes this project's renders, variance fields and disparity in the same file
formats; ``synthetic`` writes stereo renders with a known cross-view variance correlation as
files (the test data and the examples); ``generators`` reads the generators' own ground
truth by meaning (Kubric's depth TIFF and ``metadata.json``, Infinigen's frame folders and
``camview`` files); ``sample`` plans which frames of a one-render data set to render
again with two seeds for a stated power.
"""
