"""One BLAS thread unless the environment says otherwise (hil.arm.blas_threads)."""

from __future__ import annotations

import os
import subprocess
import sys

PROBE = ("import numpy; from hil.arm.blas_threads import limit_blas_threads; limit_blas_threads(); "
         "from threadpoolctl import threadpool_info; "
         "print(max(i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'))")


def _threads(**env: str) -> int:
    clean = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", PROBE], env={**clean, **env}, capture_output=True, text=True,
                         timeout=60, check=True)
    return int(out.stdout.strip())


def test_one_thread_even_when_numpy_loaded_first() -> None:
    assert _threads() == 1


def test_the_users_own_setting_is_kept_and_a_bad_one_is_no_crash() -> None:
    assert _threads(OPENBLAS_NUM_THREADS="2") == 2
    assert _threads(OPENBLAS_NUM_THREADS="abc") >= 1
