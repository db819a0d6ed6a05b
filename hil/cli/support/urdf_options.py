"""The any-arm options of the offline commands: ``--urdf FILE [--tip LINK] [--base LINK]``.

An arm that is not a catalog UR is described by its URDF; the offline commands (identify, validate, fk,
synth, export) accept it where they accept ``--robot``. The campaign, the TUI, compensation and
verification stay UR (they drive the arm through ur_rtde and the controller's own model), which every
help text that offers ``--urdf`` says (`URDF_SCOPE`).
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from hil.errors import InputError

if TYPE_CHECKING:
    from hil.arm.chain import Chain

#: What a command's help says about the any-arm path.
URDF_SCOPE = ("An arm that is not a UR is read from its URDF (--urdf, --tip, --base: offline "
              "commands only; the campaign, the TUI, compensation and verification stay UR).")


def add_urdf_options(parser: argparse.ArgumentParser) -> None:
    """``--urdf``, ``--tip`` and ``--base`` on `parser`."""
    from hil.cli.support.options import URDF_FILE

    parser.add_argument("--urdf", metavar="FILE", type=URDF_FILE,
                        help="any serial arm from its URDF instead of a catalog UR (revolute, continuous "
                             "and prismatic joints; fixed joints folded in)")
    parser.add_argument("--tip", metavar="LINK",
                        help="with --urdf: the link the SMR is mounted on (default: the end of the "
                             "URDF's only chain)")
    parser.add_argument("--base", metavar="LINK",
                        help="with --urdf: the robot base link (default: the URDF's root link)")


def urdf_chain_or_none(args: argparse.Namespace) -> Chain | None:
    """The chain ``--urdf`` names (between ``--base`` and ``--tip``), or None without ``--urdf``;
    ``--tip``/``--base`` without ``--urdf`` and ``--urdf`` beside ``--robot`` are one-line errors."""
    if args.urdf is None:
        for name in ("tip", "base"):
            if getattr(args, name, None) is not None:
                raise InputError(f"--{name} names a link of a URDF: give --urdf FILE with it")
        return None
    if getattr(args, "robot", None) is not None:
        raise InputError("--robot and --urdf both name the arm: give one (--urdf for an arm that is not "
                         "a catalog UR)")
    from hil.arm.urdf_chain import chain_from_urdf

    return chain_from_urdf(args.urdf, base=args.base, tip=args.tip)
