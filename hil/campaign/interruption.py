"""A run told to stop by a signal (`RunInterrupted`), in a module of its own that imports nothing.

The headless commands install their signal handlers (`hil.cli.support.interrupts`) before they check
their input and take the station; defined in `hil.campaign.engine`, the exception made every such
command import the engine (NumPy, the arm's geometry and routes: a fifth of a second cold) before it
could refuse a controller of another robot (issue 31: every refusal within 2 s). The engine re-exports
it, so ``hil.campaign.engine.RunInterrupted`` is the same class.
"""

from __future__ import annotations

_SIGNAL_NAMES = {2: "Ctrl-C (SIGINT)", 15: "SIGTERM", 1: "a closed terminal (SIGHUP)"}


class RunInterrupted(KeyboardInterrupt):
    """The process was told to stop by signal `signum` (SIGINT, SIGTERM, SIGHUP).

    A KeyboardInterrupt, so no ``except Exception`` on the way swallows it. Unlike `RunAborted`
    (final), an interrupted campaign stays resumable, as after ``kill -9``.
    """

    def __init__(self, signum: int = 2) -> None:
        super().__init__(signum)
        self.signum = int(signum)

    def __str__(self) -> str:
        return f"stopped by {_SIGNAL_NAMES.get(self.signum, f'signal {self.signum}')}"
