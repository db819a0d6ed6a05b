"""The exit codes are named once, for the jobs (`hil.jobs.outcome`), and are the command line's
contract: every code `hil.cli` names is the jobs' one, `hil.cli.main` returns them, and a campaign's own
`RunOutcome.exit_code` (which `run_calibration` hands on as its outcome's) says the same."""

from __future__ import annotations

import pytest

import hil.cli as cli
import hil.jobs.outcome as outcome
from hil.campaign.runner import RunOutcome

#: the documented numbers (the CLI's contract: exit codes)
DOCUMENTED = {"EXIT_OK": 0, "EXIT_FAILED": 1, "EXIT_BAD_INPUT": 2, "EXIT_FAULT": 3, "EXIT_ABORTED": 4,
              "EXIT_INTERRUPTED": 130, "EXIT_INTERNAL": 70}
#: names the command line has for a code the jobs name otherwise
CLI_ALIASES = {"EXIT_HARDWARE": "EXIT_FAULT"}


def _named(module: object) -> dict[str, int]:
    return {k: v for k, v in vars(module).items() if k.startswith("EXIT_")}


def test_the_jobs_name_the_documented_exit_codes() -> None:
    assert _named(outcome) == DOCUMENTED


def test_every_exit_code_the_command_line_names_is_the_jobs() -> None:
    named = _named(cli)
    assert {"EXIT_OK", "EXIT_BAD_INPUT", "EXIT_INTERRUPTED", "EXIT_INTERNAL"} <= set(named)
    for name, value in named.items():
        assert value == getattr(outcome, CLI_ALIASES.get(name, name)), name


def test_the_command_line_returns_the_jobs_bad_input_code(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["calibrate", "--sim", "--no-such-option"]) == outcome.EXIT_BAD_INPUT
    assert "--no-such-option" in capsys.readouterr().err


@pytest.mark.parametrize(("status", "code"), [
    ("accepted", outcome.EXIT_OK), ("rejected", outcome.EXIT_FAILED), ("aborted", outcome.EXIT_ABORTED),
    ("interrupted", outcome.EXIT_INTERRUPTED), ("failed", outcome.EXIT_FAULT)])
def test_a_campaigns_own_exit_code_is_the_jobs(status: str, code: int) -> None:
    assert RunOutcome(status, "c").exit_code == code
