"""Stored contracts and files: what the jobs write and read, and how.

``store``
    Atomic writes of results (a finished path is absent or complete), zarr datasets.
``renders``
    The render-store contract: one scene, view and SPP, a batch of seeds.
``moments``
    The moment-store contract of the ``moments`` estimator.
``contracts``
    The variance and warped stores downstream of the renders, and their provenance.
``cache``
    The content-addressed cache of single renders.
``tables``
    Result tables as CSV, Markdown, LaTeX and HTML from one list of rows.
``images``
    Image files other tools write and read: OpenEXR, PFM, PNG, NPY and NPZ.
``channels``
    Which channels of an OpenEXR file hold a render, depth, disparity or a mask.
``exr_header``
    The pixel type of each channel of an OpenEXR file, from its header alone.
``hdf5``
    BlenderProc's HDF5 files: their datasets read by name, both views of a stereo file.

Importing this package imports none of its modules (nor xarray or zarr); import the one you
need, e.g. ``from stereovar.io.store import open_dataset``.
"""
