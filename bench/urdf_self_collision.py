"""Self-collision of URDF arms: the URDF's collision meshes against capsules, speed and
agreement. Not a test: it prints a table and asserts nothing.

    python bench/urdf_self_collision.py [--count 5000] [--seed 0]

For each arm of example-robot-data (tests/hil/robot_urdfs.py), `count` postures drawn uniformly
inside its joint limits are checked three ways with hil.arm.urdf_collision.UrdfSelfCollision:

* **meshes** — the URDF's own collision geometry (the reference);
* **capsules** — hil's fallback for a URDF without geometry (one radius scaled with the arm's size,
  segments between the joint origins), forced here;
* for the Panda also **franka capsules** — Franka's own primitive collision model
  (``panda_collision.urdf``: spheres and cylinders per link, the same kinematics).

Columns: µs per posture (one thread, batched), the fraction of postures in collision, and against the
meshes the false positives (reported colliding, meshes free: candidates lost for nothing) and false
negatives (reported free, meshes colliding: postures the arm cannot take). The load average is
printed with the timings: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hil.arm.urdf_chain import chain_from_urdf
from hil.arm.urdf_collision import UrdfSelfCollision
from tests.hil.robot_urdfs import ARMS, arm, urdf_path


def _timed(check: UrdfSelfCollision, q: np.ndarray) -> tuple[np.ndarray, float]:
    check.collides(q[:16])  # warm-up
    start = time.perf_counter()
    hits = check.collides(q)
    return hits, (time.perf_counter() - start) / len(q) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--count", type=int, default=5000)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; {args.count} postures per arm")
    print(f"{'arm':8} {'check':15} {'µs/posture':>10} {'colliding':>9} {'false +':>8} {'false −':>8}  pairs")
    for name in ARMS:
        path, tip = arm(name)
        chain = chain_from_urdf(path, tip=tip)
        lo, hi = chain.sampling_range()
        q = np.random.default_rng(args.seed).uniform(lo, hi, size=(args.count, chain.dof))
        checks = [("meshes", UrdfSelfCollision(chain, path)),
                  ("capsules", UrdfSelfCollision(chain, path, capsules=True))]
        if name == "panda":
            franka = urdf_path("panda_description/urdf/panda_collision.urdf")
            checks.append(("franka capsules", UrdfSelfCollision(chain_from_urdf(franka, tip=tip), franka)))
        reference = None
        for label, check in checks:
            hits, micros = _timed(check, q)
            if reference is None:
                reference = hits
            fp, fn = np.mean(hits & ~reference), np.mean(~hits & reference)
            pairs = check._npairs if check.kind == "meshes" else len(check._pairs)
            print(f"{name:8} {label:15} {micros:10.1f} {hits.mean():9.3f} {fp:8.3f} {fn:8.3f}  {pairs}"
                  f"{'' if check.kind == 'meshes' or label == 'capsules' else ' (' + check.note + ')'}")


if __name__ == "__main__":
    main()
