"""Does a change to the identification leave its results alone? Fits the same fixed data sets with two
checkouts of hil and compares every number of the model files they write.

    python bench/same_fit.py --before DIR [--after DIR] [--rtol 1e-9]

``DIR`` is a checkout of hil (e.g. ``git archive main | tar -x -C /tmp/before``); ``--after`` defaults
to this one. Each case runs ``hil identify`` (joint errors "auto": the prior, the 10-fold
cross-validation and the forward selection of joint-error terms) on synthetic measurements of a seeded
random arm, in a fresh interpreter per checkout, and compares the two ``hil-model/1`` documents: every
string, count and flag equal, every float within ``--rtol`` relative (``--atol`` absolute, for values
that should be zero), the wall-clock fields (``seconds``, ``created``) excepted. Exit 1, naming the
first differing field of each case, if any differs.

The cases: a rigid UR5e (40 poses), a realistic UR10e (compliance, payload, joint errors and lost
motion; 60 poses approached from alternating sides, fitted with ``--compliance``), and the rigid arm
without the prior (``--no-prior``).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

#: Fields that say when or how long, not what was fitted.
CLOCK_FIELDS = frozenset({"seconds", "created", "generated"})


def make_cases(folder: Path) -> list[tuple[str, list[str]]]:
    """(name, ``hil identify`` arguments) of each case, its measurements written in `folder`."""
    import numpy as np

    from hil.calibration.measurements import write_measurements
    from hil.calibration.synthetic import (
        Noise,
        approach_directions,
        measure,
        random_configurations,
        random_truth,
    )

    rng = np.random.default_rng(29)
    rigid = random_truth("ur5e", rng, rigid=True)
    q, p = measure(rigid, random_configurations("ur5e", 40, rng), Noise(), rng)
    write_measurements(folder / "rigid.csv", q, p)
    real = random_truth("ur10e", rng, ideal=False)
    q_cmd = random_configurations("ur10e", 60, rng)
    d = approach_directions(q_cmd)
    d[1::2] *= -1.0  # half the poses approached from the other side: lost motion becomes observable
    q, p = measure(real, q_cmd, Noise(), rng, directions=d)
    write_measurements(folder / "real.csv", q, p, d)
    return [
        ("rigid ur5e, 40 poses", ["--robot", "ur5e", "--measurements", str(folder / "rigid.csv")]),
        ("realistic ur10e, 60 poses, --compliance",
         ["--robot", "ur10e", "--measurements", str(folder / "real.csv"), "--compliance"]),
        ("rigid ur5e, --no-prior", ["--robot", "ur5e", "--measurements", str(folder / "rigid.csv"),
                                    "--no-prior"]),
    ]


def fit(source: Path, args: list[str], out: Path) -> dict[str, Any]:
    """The model document ``hil identify ARGS`` of the hil in `source` writes."""
    env = dict(os.environ, PYTHONPATH=str(source.resolve()))
    env.pop("HIL_DB", None)
    done = subprocess.run([sys.executable, "-m", "hil", "identify", *args, "--out", str(out)], env=env,
                          cwd=source, capture_output=True, text=True, check=False)
    if done.returncode not in (0, 1):  # 1: fitted, but not shown better than nominal
        sys.exit(f"{source}: hil identify {' '.join(args)}: exit {done.returncode}: {done.stderr[-500:]}")
    return json.loads(out.read_text(encoding="utf-8"))


def first_difference(a: Any, b: Any, rtol: float, atol: float, where: str = "") -> str | None:
    """Where `a` and `b` first differ beyond the tolerances (None: they agree)."""
    if isinstance(a, dict) and isinstance(b, dict):
        if a.keys() != b.keys():
            return f"{where or '.'}: keys {sorted(a.keys() ^ b.keys())} in one only"
        for k in a:
            if k in CLOCK_FIELDS:
                continue
            found = first_difference(a[k], b[k], rtol, atol, f"{where}.{k}")
            if found:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            return f"{where}: {len(a)} items against {len(b)}"
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            found = first_difference(x, y, rtol, atol, f"{where}[{i}]")
            if found:
                return found
        return None
    if isinstance(a, float) or isinstance(b, float):
        if isinstance(a, bool) or isinstance(b, bool) or not isinstance(a, int | float) \
                or not isinstance(b, int | float):
            return f"{where}: {a!r} against {b!r}"
        if math.isclose(a, b, rel_tol=rtol, abs_tol=atol) or (math.isnan(a) and math.isnan(b)):
            return None
        return f"{where}: {a!r} against {b!r} (relative {abs(a - b) / max(abs(a), abs(b)):.2e})"
    return None if a == b else f"{where}: {a!r} against {b!r}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", type=Path, required=True, help="the checkout of hil to compare against")
    ap.add_argument("--after", type=Path, default=ROOT, help="the checkout compared (default: this one)")
    ap.add_argument("--rtol", type=float, default=1e-9, help="relative tolerance (default 1e-9)")
    ap.add_argument("--atol", type=float, default=1e-15,
                    help="absolute tolerance, for values that should be zero (default 1e-15)")
    args = ap.parse_args()
    failed = False
    with tempfile.TemporaryDirectory(prefix="hil-same-fit-") as tmp:
        folder = Path(tmp)
        for k, (name, argv) in enumerate(make_cases(folder)):
            before = fit(args.before, argv, folder / f"before{k}.json")
            after = fit(args.after, argv, folder / f"after{k}.json")
            found = first_difference(before, after, args.rtol, args.atol)
            print(f"{name:<42} {'same' if found is None else 'DIFFERS: ' + found}")
            failed |= found is not None
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
