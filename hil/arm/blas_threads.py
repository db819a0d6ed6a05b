"""One BLAS thread per process: hil's matrices are small, and threads make them slower.

hil multiplies and factorises matrices of tens of columns (identification Jacobians, information
matrices of the pose selection, 4 × 4 frames), thousands of times in a row. OpenBLAS splits each such
product over its threads and synchronises them every call, which costs more than the arithmetic; on
a station PC that also runs the controller link, the tracker link and the terminal, the threads wait
for cores as well. Measured on a 2-core machine, ``hil select --robot ur5e --count 12 --candidates
3000`` took 11.2 s wall and 12.9 s CPU with OpenBLAS's default threads, 6.1 s wall and 4.2 s CPU with
one. Parallel work that pays (candidate generation in worker processes, runs of several stations)
is done by processes, each with its one BLAS thread.
"""

from __future__ import annotations

import os
import sys

#: the variables OpenBLAS (numpy's and scipy's wheels) and OpenMP read when they load
_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")

_limits: object | None = None


def limit_blas_threads() -> None:
    """One BLAS thread in this process and the processes it starts, unless the environment already
    says how many (idempotent).

    Before numpy loads, the environment decides; once it has loaded, threadpoolctl changes the
    loaded library's setting.
    """
    global _limits
    ours = "OPENBLAS_NUM_THREADS" not in os.environ  # a setting of the user's: OpenBLAS reads it itself
    for name in _VARIABLES:
        os.environ.setdefault(name, "1")
    if ours and _limits is None and "numpy" in sys.modules:
        from threadpoolctl import threadpool_limits

        _limits = threadpool_limits(limits=1, user_api="blas")
