"""The export formats a command offers (``--format``) and the one a file's suffix says, named without
importing the exporters (`hil.calibration.exports`, which stands on numpy): ``hil show`` and ``hil
robot`` list the store and only sometimes export, and their start-up must not pay for it
(bench/cli_startup.py). tests/hil/cli/test_listing_imports.py checks the names against the exporters'.
"""

from __future__ import annotations

from pathlib import Path

#: `hil.calibration.exports.FORMATS`, in its order
FORMATS: tuple[str, ...] = ("urdf", "ros-kinematics", "json")

#: file suffixes that say which export format is meant when ``--format`` is not given
SUFFIX_FORMATS = {".urdf": "urdf", ".xml": "urdf", ".yaml": "ros-kinematics", ".yml": "ros-kinematics",
                  ".json": "json"}


def format_of(path: str, given: str | None = None) -> str:
    """The format `given` (``--format``), else the one `path`'s suffix says, else JSON."""
    return given or SUFFIX_FORMATS.get(Path(path).suffix.lower(), "json")
