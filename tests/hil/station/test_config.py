import pytest

from hil.errors import InputError
from hil.station.config import EXAMPLE, default_config, load_config, parse_config


def test_example_is_valid_and_complete():
    cfg = load_config(EXAMPLE)
    assert cfg.robot["type"] == "ur5e" and cfg.get("campaign.calibration_poses") == 30
    assert cfg.tracker["position"] is None and cfg.smr["offset"] == (0.0, 0.0, 0.045)
    assert set(cfg.as_dict()) == set(default_config().as_dict())


@pytest.mark.parametrize("text,message", [
    ("[robot]\nspeed = -1\n", r"robot.speed: must be in \(0, 3.14\] rad/s, got -1"),
    ("[robot]\nsped = 1\n", "unknown key robot.sped"),
    ("[robots]\ntype = 'ur5e'\n", r"unknown section \[robots\]"),
    ("[robot]\ntype = 'abb'\n", "robot.type: unknown robot 'abb'"),
    ("[campaign]\nsamples = 2.5\n", "campaign.samples: must be an integer"),
    ("[tracker]\nposition = [1, 2]\n", r"tracker.position: must be a list of three numbers"),
    ("[smr]\nacceptance_angle = 95\n", r"smr.acceptance_angle: must be in \(0, 90\) degrees, got 95"),
    ("[keep_in]\nmin = [0, 0, 0]\nmax = [1, 1, 0]\n", "keep_in.min must be below keep_in.max"),
    ("[robot\n", "not valid TOML"),
])
def test_bad_values_name_the_key(tmp_path, text, message):
    path = tmp_path / "station.toml"
    path.write_text(text)
    with pytest.raises(InputError, match=message) as info:
        load_config(path)
    assert str(info.value).startswith(str(path))


def test_overrides_are_revalidated():
    cfg = default_config().with_overrides(robot__address="127.0.0.9")
    assert cfg.robot["address"] == "127.0.0.9"
    with pytest.raises(InputError):
        parse_config({"campaign": {"acceptance": "tiny"}})
