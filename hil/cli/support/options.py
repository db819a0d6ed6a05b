"""The command line's option types and parsers, shared by the subcommands: every number is a row of the
physical-quantity table (`hil.files.quantities`), the same one the files are read against, so bad input
is one usage line (exit 2) naming the option and the quantity's range before anything runs."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from hil.errors import InputError
from hil.files.quantities import check_vector, quantity

if TYPE_CHECKING:
    import numpy as np


def option(name: str) -> Callable[[str], Any]:
    """argparse ``type`` of the quantity `name` of `hil.files.quantities.QUANTITIES`: NaN, infinities,
    denormals and values outside its range are a one-line usage error naming the option and the range
    (exit 2). A bare ``type=float`` lets ``inf`` hang a loop and ``1e30`` ask numpy for terabytes."""
    return quantity(name).option()


def triplet_or_none(text: str | None, option: str, quantity_name: str, *, norm: bool = False
                    ) -> np.ndarray | None:
    """An optional "X,Y,Z" option of quantity `quantity_name` (each component in its range, or with
    ``norm`` the vector's length) as a vector; InputError naming the option when malformed or out of range."""
    import numpy as np

    from hil.arm.geometry import parse_triplet  # pinocchio: not for commands that only print help

    if text is None:
        return None
    vector = parse_triplet(text, option)
    return np.array(check_vector(vector.tolist(), quantity_name, option, norm=norm))


PAYLOAD_HELP = ("what the arm carries: MASS,X,Y,Z (kg, and its centre of mass in the flange frame, m); "
                "0 for nothing")


def payload_or_none(text: str | None, option: str = "--payload") -> Any:
    """An optional ``--payload MASS,X,Y,Z`` as a `hil.arm.payload.Payload` (InputError naming the
    option when malformed); ``0`` is an empty flange. A mass without its centre of mass is refused: the
    torque the joints sag under is mass × lever arm, and a centre of mass silently put on the flange
    face (the old default) made every sag prediction with a payload wrong by its real lever arm."""
    from hil.arm.payload import Payload

    if text is None:
        return None
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"{option}: expected MASS,X,Y,Z (kg, m) or 0, got {text!r}") from None
    if len(values) == 1 and values[0] == 0:
        return Payload.from_dict({"mass": 0.0, "com": [0.0, 0.0, 0.0]}, option)
    if len(values) == 1:
        quantity("payload mass").check(values[0], option, parts[0])
        raise InputError(f"{option}: {parts[0]} kg without its centre of mass: give MASS,X,Y,Z (the centre "
                         "of mass in the flange frame, m, as Polyscope's Payload setting shows it)")
    if len(values) != 4:
        raise InputError(f"{option}: expected MASS,X,Y,Z (kg, m), got {len(values)} numbers")
    return Payload.from_dict({"mass": values[0], "com": values[1:]}, option)


def input_file(expected: str, limit: int | None = None) -> Callable[[str], str]:
    """argparse ``type`` of an option naming an input file of kind `expected` ("a JSON file"): the
    path, unchanged, when `hil.files.inputs.check_input_file` finds it a regular file within `limit`
    bytes; else a one-line usage error naming the option and the file (exit 2). Checked while the
    command line is parsed, before a command loads the libraries it computes with (``hil report``'s
    matplotlib, ``hil verify``'s station), a FIFO or a folder given as a model is refused in a
    fraction of a second rather than after seconds of imports."""
    from hil.files import inputs

    def check(text: str) -> str:
        import argparse
        import os

        if not os.path.lexists(text):  # named by its reader, after the options' values are checked
            return text
        try:
            inputs.check_input_file(text, expected, inputs.MAX_INPUT_BYTES if limit is None else limit)
        except InputError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None
        return text

    check.__name__ = expected  # argparse names the type in some of its own messages
    return check


#: The kinds of input file options name (`input_file`), each bounded as its reader bounds it.
JSON_FILE = input_file("a JSON file", 16 << 20)
CSV_FILE = input_file("a CSV file")
TOML_FILE = input_file("a TOML file", 1 << 20)
MOVEB_FILE = input_file("a MOVEB program")
POSES_OR_PROGRAM = input_file("a CSV of poses or a URScript program")
#: A robot description: real arms' URDFs are tens of kB (example-robot-data); meshes are separate files.
URDF_FILE = input_file("a URDF file", 16 << 20)


#: ``--joint-units``: the unit of joint columns whose names carry no unit suffix (docs/design.md, Contracts:
#: Measurements CSV). Declared, never guessed from the values.
JOINT_UNITS: tuple[str, ...] = ("rad", "deg")
JOINT_UNITS_HELP = ("unit of the joint columns whose names carry no unit suffix (default rad; a header "
                    "q1_deg..q6_deg declares degrees itself)")


def add_joint_units(parser: Any) -> None:
    """The ``--joint-units rad|deg`` option of every command that reads joint angles from a CSV."""
    parser.add_argument("--joint-units", choices=JOINT_UNITS, default=None, help=JOINT_UNITS_HELP)


#: Largest plausible RMS acceptance threshold (m), the "rms threshold" row of the quantity table.
MAX_RMS_THRESHOLD = quantity("rms threshold").high
RMS_THRESHOLD_HELP = "in METRES, e.g. 0.0001 for 0.1 mm, at most 0.01 = 10 mm"

#: An RMS acceptance threshold in metres (``--accept``, ``--max-rms``).
rms_threshold = option("rms threshold")

#: Random seeds: numpy's generators take any non-negative integer, and 32 bits are all a seed needs to
#: tell runs apart (``--seed -1`` made numpy raise deep inside the simulator: exit 70).
SEED = option("seed")

#: Fast-time factor of the simulated station (``--speed``): ``inf`` hung ``hil calibrate --sim`` and 0
#: or NaN stop simulated time.
SIM_SPEED = option("simulated speed")

#: Poses of a campaign or a selection (``--poses``, ``--validation``, ``--count``); the configuration's
#: ``campaign.*_poses`` keys are the same row.
POSE_COUNT = option("pose count")

#: Visits of each validation pose (``--cycles``).
CYCLES = option("visits")

#: Cycles of the ISO 9283 pose test (``hil verify --cycles``, ``hil calibrate --verify-cycles``).
VERIFY_CYCLES = option("cycles")

#: Candidate configurations for the selector (``--candidates``; ``campaign.candidates`` is the same row).
MAX_CANDIDATES = int(quantity("candidates").high)
CANDIDATES = option("candidates")
