"""The exit codes are named once for the jobs (`hil.jobs.outcome`) and the command line uses them
(`hil.cli`): the two must say the same number for the same end, and so must a campaign's own
`RunOutcome.exit_code`, which `run_calibration` hands on as its outcome's."""

from __future__ import annotations

import pytest

import hil.cli as cli
import hil.jobs.outcome as outcome
from hil.campaign.runner import RunOutcome

# (hil.cli's name, hil.jobs.outcome's name, the documented number)
CODES = [
    ("EXIT_OK", "EXIT_OK", 0),
    ("EXIT_FAILED", "EXIT_FAILED", 1),
    ("EXIT_BAD_INPUT", "EXIT_BAD_INPUT", 2),
    ("EXIT_HARDWARE", "EXIT_FAULT", 3),
    ("EXIT_ABORTED", "EXIT_ABORTED", 4),
    ("EXIT_INTERRUPTED", "EXIT_INTERRUPTED", 130),
    ("EXIT_INTERNAL", "EXIT_INTERNAL", 70),
]


@pytest.mark.parametrize(("cli_name", "job_name", "number"), CODES)
def test_the_jobs_and_the_command_line_say_the_same_exit_code(
        cli_name: str, job_name: str, number: int) -> None:
    assert getattr(outcome, job_name) == getattr(cli, cli_name) == number


def test_every_exit_code_the_jobs_name_is_listed_and_distinct() -> None:
    named = {k: v for k, v in vars(outcome).items() if k.startswith("EXIT_")}
    assert set(named) == {job for _, job, _ in CODES}
    assert len(set(named.values())) == len(named)


@pytest.mark.parametrize(("status", "code"), [
    ("accepted", outcome.EXIT_OK), ("rejected", outcome.EXIT_FAILED), ("aborted", outcome.EXIT_ABORTED),
    ("interrupted", outcome.EXIT_INTERRUPTED), ("failed", outcome.EXIT_FAULT)])
def test_a_campaigns_own_exit_code_is_the_jobs(status: str, code: int) -> None:
    assert RunOutcome(status, "c").exit_code == code
