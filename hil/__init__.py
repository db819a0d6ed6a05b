"""hil: hardware-in-the-loop kinematic calibration of Universal Robots arms."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("hil")
except PackageNotFoundError:  # running from a source checkout that is not installed
    __version__ = "0.1.0+src"
