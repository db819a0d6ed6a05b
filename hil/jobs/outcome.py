"""How a job ended, in terms every front-end can act on: an exit code, a status and what to say.

The exit codes are the CLI's contract (docs/design.md, Contracts: exit codes) and are named here once,
so no job or command returns a literal number. A job never prints: what the operator must be told
(a fault, "resumable: re-run the same command") it says through its `hil.jobs.words.Say` callback.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

EXIT_OK = 0  # done: accepted, finished
EXIT_FAILED = 1  # ran, but did not pass: a calibration above its threshold, a path measured too little
EXIT_BAD_INPUT = 2  # a file, a flag, a configuration value; one line naming it
EXIT_FAULT = 3  # the station: a device or a database that does not answer, a fault that ended the run
EXIT_ABORTED = 4  # aborted by the operator (final)
EXIT_INTERRUPTED = 130  # Ctrl-C; in general 128 + the signal number (143 SIGTERM, 129 SIGHUP)
EXIT_INTERNAL = 70  # a bug: one line (``--debug`` shows the traceback)


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
