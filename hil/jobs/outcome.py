"""How a job ended, in terms every front-end can act on: an exit code, a status and what to say.

The exit codes are the CLI's contract (docs/design.md, Contracts: exit codes), named once in
`hil.errors` beside the errors they answer (a campaign's own outcome uses them too) and handed on here,
so no job or command returns a literal number. A job never prints: what the operator must be told
(a fault, "resumable: re-run the same command") it says through its `hil.jobs.words.Say` callback.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from hil.errors import (
    EXIT_ABORTED,
    EXIT_BAD_INPUT,
    EXIT_FAILED,
    EXIT_FAULT,
    EXIT_INTERNAL,
    EXIT_INTERRUPTED,
    EXIT_OK,
)

__all__ = ["EXIT_ABORTED", "EXIT_BAD_INPUT", "EXIT_FAILED", "EXIT_FAULT", "EXIT_INTERNAL", "EXIT_INTERRUPTED",
           "EXIT_OK", "JobOutcome"]


@dataclass
class JobOutcome:
    """The end of a job: its exit code, its status, its campaign (if it has one) and its document.

    `document` is what the job's ``--out`` writes (a ``hil-result/1``, a ``hil-verification/1``, a
    ``hil-moveb-run/1``), None when there is nothing to write (a run that did not finish, whose
    earlier output file must stay as it was).
    """

    exit_code: int
    status: str
    campaign: str = ""
    document: dict[str, Any] | None = None
