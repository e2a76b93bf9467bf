"""stereovar: cross-view Monte Carlo variance correlation in path-traced stereo.

Importing the package is cheap and pulls in no third-party module (numpy, Dr.Jit, Mitsuba),
so that set-up scripts can use :mod:`stereovar.backend` with the system Python before the
dependencies are installed. Import submodules explicitly, e.g. ``stereovar.backend``.
"""

__version__ = "0.1.0"
