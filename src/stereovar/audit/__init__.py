"""Audits of renders made elsewhere: import, sign check, verdict and export.

``layout`` finds an audit's files from path templates; ``importer`` writes them into the
render and ground-truth store contracts (with provenance and SHA-256s, re-importing only what
changed); ``ground_truth`` builds the imported ground truth; ``sign`` settles the disparity
convention photometrically; ``verdict`` writes the one-page verdict; ``export`` writes this
project's renders, variance fields and disparity in the same file formats.
"""
