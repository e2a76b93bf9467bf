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
    Reading image files other tools write: renders, fields and segment ids, whatever the format.
``formats``
    The image file formats by extension: OpenEXR, PFM, PNG, NPY, NPZ, HDF5 and TIFF.
``transfer``
    The sRGB transfer function of integer images, decoding and encoding.
``files``
    Opening a user's files: regular files only, each failure one line.
``headers``
    What an image file's header says, no pixel decoded: size, half floats, integer bits.
``decoders``
    The pixels of each image format as its library decodes them.
``pfm``
    PFM files, read and written by hand.
``writers``
    Image and field files written in the format of a path's extension.
``channels``
    Which channels of an OpenEXR file hold a render, depth, disparity or a mask.
``exr_header``
    The pixel type of each channel of an OpenEXR file, from its header alone.
``hdf5``
    BlenderProc's HDF5 files: their datasets read by name, both views of a stereo file.

Importing this package imports none of its modules (nor xarray or zarr); import the one you
need, e.g. ``from stereovar.io.store import open_dataset``.
"""
