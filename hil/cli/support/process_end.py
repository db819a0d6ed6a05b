"""Ending a process that has closed everything it opened, without the interpreter's teardown.

After ``hil tui`` has stopped the arm, recorded the campaign, closed the devices, the store and the
simulator and given the terminal back, Python's own shutdown still collects and frees every object of
the ~1700 modules the app loaded (Textual, SQLAlchemy, numpy, pinocchio...): measured with
``strace`` at 80x24 after a quit mid-measure, 4.9 s without a single system call between the last
atexit handler and ``exit_group`` on a loaded 2-core machine (load average 24; ``gc.collect`` alone
took 1.3 s of it), while the operator waits for the prompt with nothing left to do. `end_process`
runs what must still run (the atexit handlers: multiprocessing's, logging's flush; the standard
streams' flush) and then ends the process at once.
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import sys
from typing import NoReturn


def end_process(code: int) -> NoReturn:
    """Exit with `code` now: atexit handlers and stream flushes run, the interpreter's teardown
    (garbage collection and freeing of every module) is skipped. Only for a process whose every
    resource is already closed."""
    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)  # CPython: what a normal exit runs
    if run_exit_handlers is not None:
        run_exit_handlers()
    else:  # another interpreter: at least the log records
        logging.shutdown()
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # closed, or its reader gone: nothing to say
            stream.flush()
    os._exit(code)
