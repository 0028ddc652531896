"""Single source of the package version (read by the build and by ``slslam.__version__``)."""

__version__ = "0.1.0"
