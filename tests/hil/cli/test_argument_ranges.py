"""Every numeric option of every subcommand has a range: bad values are argparse's one line, exit 2.

Issue 19: ``--seed -1`` (synth, select, calibrate --sim, moveb run, sim) and ``--candidates 1e9``,
``--step 1e-9``, ``--velocity 1e30``, ``sim --control-port 99999`` ended in exit 70 (internal error);
``calibrate --sim --speed inf`` and ``select --start 1e300,...`` hung; ``select --start 20,...`` (outside
the joint limits) was accepted; ``--velocity 1e30`` wrote s.csv before failing. Each case here must exit
2 with one line naming the option, write nothing, start nothing, and finish within its time limit.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.cli import build_parser, main

ROOT = Path(__file__).resolve().parents[3]
PROGRAM = str(ROOT / "hil" / "moveb" / "examples" / "square.moveb")

CAL = ["calibrate", "--sim", "--db", "k.db", "--out", "r.json"]
SYNTH = ["synth", "--out-dir", "synth-out"]
SELECT = ["select", "--robot", "ur5e", "--count", "12", "--candidates", "300", "--no-bound", "--quiet",
          "--out", "poses.json"]
PLAN = ["moveb", "plan", PROGRAM, "--out", "s.csv"]
RUN = ["moveb", "run", PROGRAM, "--sim", "--out", "run.json"]
TUI = ["tui", "--sim", "--db", "tui.db"]
IDENTIFY = ["identify", "--robot", "ur5e", "--measurements", "m.csv", "--out", "model.json"]
VALIDATE = ["validate", "--model", "model.json", "--measurements", "v.csv"]

#: (command line, the option its one-line error must name)
BAD: list[tuple[list[str], str]] = [
    # the values
    ([*CAL, "--seed", "-1"], "--seed"),
    ([*SYNTH, "--seed", "-1"], "--seed"),
    ([*SELECT, "--seed", "-1"], "--seed"),
    ([*RUN, "--seed", "-1"], "--seed"),
    (["sim", "--seed", "-1"], "--seed"),
    ([*TUI, "--seed", "-1"], "--seed"),
    ([*CAL, "--speed", "inf"], "--speed"),
    ([*SELECT, "--start", "1e300,0,0,0,0,0"], "--start"),
    ([*SELECT, "--start", "20,0,0,0,0,0"], "--start"),
    ([*SELECT, "--start", "0,0,4,0,0,0"], "--start"),  # the elbow turns at most ±π
    ([*SELECT, "--candidates", "1000000000"], "--candidates"),
    ([*VALIDATE, "--max-rms", "-1"], "--max-rms"),
    ([*VALIDATE, "--max-rms", "nan"], "--max-rms"),
    (["sim", "--control-port", "99999"], "--control-port"),
    ([*PLAN, "--step", "1e-9"], "--step"),
    ([*PLAN, "--velocity", "1e30"], "--velocity"),
    # calibrate and tui
    ([*CAL, "--speed", "1e308"], "--speed"),
    ([*CAL, "--speed", "nan"], "--speed"),
    ([*CAL, "--speed", "0"], "--speed"),
    ([*CAL, "--poses", "100000000"], "--poses"),
    ([*CAL, "--validation", "0"], "--validation"),
    ([*CAL, "--candidates", "1000000000"], "--candidates"),
    ([*CAL, "--cycles", "1000000"], "--cycles"),
    ([*TUI, "--speed", "inf"], "--speed"),
    ([*TUI, "--poses", "100000000"], "--poses"),
    ([*TUI, "--poses", "3"], "--poses"),
    ([*TUI, "--candidates", "1000000000"], "--candidates"),
    # synth
    ([*SYNTH, "--poses", "1000000000"], "--poses"),
    ([*SYNTH, "--validation", "1000000000"], "--validation"),
    ([*SYNTH, "--noise", "1e308"], "--noise"),
    ([*SYNTH, "--noise", "1"], "--noise"),
    # select
    ([*SELECT, "--count", "1000000000"], "--count"),
    ([*SELECT, "--floor", "1e308"], "--floor"),
    ([*SELECT, "--half-angle", "90"], "--half-angle"),
    ([*SELECT, "--wrist-margin", "180"], "--wrist-margin"),
    ([*SELECT, "--elbow-margin", "-1"], "--elbow-margin"),
    ([*SELECT, "--shoulder-margin", "1e308"], "--shoulder-margin"),
    ([*SELECT, "--tracker", "1e308,0,0"], "--tracker"),
    ([*SELECT, "--smr", "10,0,0"], "--smr"),
    ([*SELECT, "--keep-in", "-1e308,-1,0,1e308,1,1"], "--keep-in"),
    ([*SELECT, "--keep-in", "1,1,1,0,0,0"], "--keep-in"),
    ([*SELECT, "--range", "0,1e300"], "--range"),
    ([*SELECT, "--range", "-1,2"], "--range"),
    # identify
    ([*IDENTIFY, "--smr", "10,0,0"], "--smr"),
    ([*IDENTIFY, "--smr", "1e308,0,0"], "--smr"),
    # sim
    (["sim", "--control-port", "-1"], "--control-port"),
    (["sim", "--speed", "inf"], "--speed"),
    (["sim", "--speed-slider", "2"], "--speed-slider"),
    (["sim", "--encoder-noise", "1"], "--encoder-noise"),
    (["sim", "--baud", "0"], "--baud"),
    (["sim", "--acceptance-angle", "90"], "--acceptance-angle"),
    (["sim", "--address", "127.0.0.256"], "--address"),
    # moveb plan and run
    ([*PLAN, "--rate", "1e308"], "--rate"),
    ([*PLAN, "--jerk", "1e308"], "--jerk"),
    ([*PLAN, "--acceleration", "0"], "--acceleration"),
    ([*PLAN, "--normal-acceleration", "nan"], "--normal-acceleration"),
    ([*RUN, "--velocity", "1e30"], "--velocity"),
    ([*RUN, "--speed", "inf"], "--speed"),
    ([*RUN, "--tracker-rate", "1e308"], "--tracker-rate"),
    ([*RUN, "--joint-acceleration", "inf"], "--joint-acceleration"),
    ([*RUN, "--joint-speed", "2"], "--joint-speed"),
    ([*RUN, "--min-coverage", "1.5"], "--min-coverage"),
    # history
    (["history", "--db", "k.db", "--limit", "1000000000000000000000"], "--limit"),
]


@pytest.fixture
def nothing_starts(monkeypatch: pytest.MonkeyPatch) -> None:
    """The simulated station, the hardware, `hil sim`'s server and the TUI app fail the test if
    reached: bad values must be refused before any of them starts."""
    import hil.station.devices
    import hil.tui.app
    import mocks.station
    import mocks.ur.process

    def tripwire(*args: object, **kwargs: object) -> None:
        raise AssertionError("started before refusing the bad value")

    monkeypatch.setattr(mocks.station, "start_station", tripwire)
    monkeypatch.setattr(mocks.ur.process, "serve", tripwire)
    monkeypatch.setattr(hil.station.devices, "open_devices", tripwire)
    monkeypatch.setattr(hil.station.devices, "ask_controller", tripwire)  # asking it connects too
    monkeypatch.setattr(hil.tui.app, "create_app", tripwire)


@pytest.mark.timeout(60)  # `--speed inf` and `--start 1e300` hung: a hang fails instead of blocking
@pytest.mark.parametrize(("argv", "option"), BAD, ids=[" ".join(a[a.index(o):]) if o in a else o
                                                      for a, o in BAD])
def test_bad_value_is_one_line_exit_2_and_nothing_is_written(
        argv: list[str], option: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str], nothing_starts: None) -> None:
    monkeypatch.chdir(tmp_path)  # every relative output (k.db, s.csv, poses.json ...) lands here
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert len(captured.err.strip().splitlines()) == 1, captured.err
    assert option in captured.err and "Traceback" not in captured.err, captured.err
    assert captured.out == ""
    assert list(tmp_path.iterdir()) == [], "a bad value left a file behind"


#: In range, at the edges: parsed as given (the ranges are physical, not a list of the defaults).
GOOD: list[tuple[list[str], str, object]] = [
    ([*CAL, "--speed", "1000"], "speed", 1000.0),
    ([*CAL, "--seed", "0"], "seed", 0),
    ([*CAL, "--seed", "4294967295"], "seed", 2**32 - 1),
    ([*CAL, "--poses", "1000"], "poses", 1000),
    ([*CAL, "--candidates", "200000"], "candidates", 200_000),
    ([*CAL, "--cycles", "30"], "cycles", 30),
    ([*SYNTH, "--noise", "0"], "noise", 0.0),
    ([*SELECT, "--half-angle", "89.9"], "half_angle", 89.9),
    ([*SELECT, "--floor", "-0.5"], "floor", -0.5),
    (["sim", "--control-port", "0"], "control_port", 0),
    (["sim", "--control-port", "65535"], "control_port", 65535),
    (["sim", "--address", "127.3.4.5"], "address", "127.3.4.5"),
    ([*PLAN, "--step", "0.01"], "step", 0.01),
    ([*PLAN, "--velocity", "3000"], "velocity", 3000.0),
    ([*PLAN, "--rate", "125"], "rate", 125.0),
    ([*RUN, "--joint-acceleration", "40"], "joint_acceleration", 40.0),
    ([*RUN, "--tracker-rate", "1000"], "tracker_rate", 1000.0),
    (["history", "--limit", "1"], "limit", 1),
]


@pytest.mark.parametrize(("argv", "dest", "value"), GOOD, ids=[" ".join(a[-2:]) for a, _, _ in GOOD])
def test_values_at_the_edges_are_accepted(argv: list[str], dest: str, value: object) -> None:
    args = build_parser(argv).parse_args(argv)
    assert getattr(args, dest) == value


@pytest.mark.timeout(120)
def test_select_starts_from_a_configuration_inside_the_joint_limits(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """The --start check refuses only what is outside the limits: a real start still selects."""
    monkeypatch.chdir(tmp_path)
    assert main([*SELECT, "--start", "0.5,-1.2,1.0,-6.2,1.2,6.2"]) == 0, capsys.readouterr().err
    assert (tmp_path / "poses.json").exists()


def test_the_two_candidate_ceilings_agree() -> None:
    """``--candidates`` and ``campaign.candidates`` overriding each other must mean the same."""
    from hil.cli.support.options import MAX_CANDIDATES
    from hil.station import config

    assert MAX_CANDIDATES == config.MAX_CANDIDATES
