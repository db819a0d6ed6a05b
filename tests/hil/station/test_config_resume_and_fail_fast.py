"""Issue 19, "Resume and fail-fast": the configuration refuses a calibration pose count the fit cannot
identify from (before anything connects or moves), and declares how many poses in a row may lose the
beam before a run stops."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from hil.arm.catalog import ROBOT_NAMES
from hil.arm.kinematics import (
    N_ALL_PARAMETERS,
    N_PARAMETERS,
    identifiable_parameters,
    identifiable_with_compliance,
)
from hil.errors import InputError
from hil.station import config as config_module
from hil.station.config import EXAMPLE, default_config, load_config, parse_config
from selector.design import minimum_poses

ROOT = Path(__file__).resolve().parents[3]


@pytest.mark.parametrize("compliance", [True, False])
@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_fewer_calibration_poses_than_identify_the_robot_are_refused_naming_the_key(robot, compliance):
    # with the compliance (the default) the joints a floor arm's gravity loads count too
    n = len(identifiable_with_compliance(robot) if compliance else identifiable_parameters(robot))
    need = minimum_poses(n)
    data = {"robot": {"type": robot}, "campaign": {"calibration_poses": need - 1, "compliance": compliance}}
    with pytest.raises(InputError) as caught:
        parse_config(data, "station.toml")
    assert str(caught.value) == (f"station.toml: campaign.calibration_poses: {need - 1} is too few: "
                                 f"identifying the {n} parameters of a {robot} from 3 coordinates per "
                                 f"pose needs at least {need}")
    data["campaign"]["calibration_poses"] = need
    assert parse_config(data, "station.toml").campaign["calibration_poses"] == need


def test_the_cheap_bound_is_every_parameter_of_the_model():
    # counts of at least minimum_poses(every parameter) skip the kinematics: that must stay sufficient
    assert config_module._ALL_PARAMETERS == N_PARAMETERS
    assert config_module._ALL_PARAMETERS + 6 == N_ALL_PARAMETERS  # and the six compliances
    assert all(len(identifiable_parameters(r)) <= N_PARAMETERS for r in ROBOT_NAMES)
    assert all(len(identifiable_with_compliance(r)) <= N_ALL_PARAMETERS for r in ROBOT_NAMES)


def test_reading_a_usual_configuration_does_not_load_the_kinematics():
    code = ("import sys\nfrom hil.station.config import load_config\n"
            f"load_config({str(EXAMPLE)!r})\nprint('pinocchio' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == "False", out.stderr


def test_max_consecutive_lost_defaults_to_three_and_is_range_checked():
    assert default_config().campaign["max_consecutive_lost"] == 3
    assert load_config(EXAMPLE).campaign["max_consecutive_lost"] == 3
    assert parse_config({"campaign": {"max_consecutive_lost": 1}}).campaign["max_consecutive_lost"] == 1
    for bad, says in ((0, r"must be in \[1, 100\], got 0"), (101, r"must be in \[1, 100\], got 101"),
                      (2.5, "must be an integer"), (True, "must be an integer")):
        with pytest.raises(InputError, match=f"station.toml: campaign.max_consecutive_lost: .*{says}"):
            parse_config({"campaign": {"max_consecutive_lost": bad}}, "station.toml")
