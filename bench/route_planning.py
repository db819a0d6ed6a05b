"""CPU time of route planning: `Router.route` between random poses of a UR10e in the example station's
keep-in box, where the straight path often leaves the box and detours are tried (every leg of every
candidate route is a keep-in check, `hil.arm.safety.check_target`).

    python bench/route_planning.py [--legs 200] [--repeat 3] [--source DIR]

Prints the legs routed, how many went straight, by a detour or found no safe way, and the CPU time per
leg (the best of `--repeat` passes: CPU time, so a loaded machine disturbs it less than wall time).
``--source DIR`` plans with another checkout of hil (e.g. ``git archive main | tar -x -C /tmp/before``)
for a before/after comparison; the poses are the same (seeded) either way.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--legs", type=int, default=200, help="legs to route (default 200)")
    ap.add_argument("--repeat", type=int, default=3, help="passes; the fastest is shown (default 3)")
    ap.add_argument("--source", type=Path, help="plan with the hil in this directory instead")
    args = ap.parse_args()
    sys.path.insert(0, str((args.source or Path(__file__).resolve().parents[1]).resolve()))
    import numpy as np

    from hil.arm.catalog import get_robot
    from hil.arm.geometry import Geometry
    from hil.arm.routes import Router, UnsafePathError
    from hil.errors import HilError
    from hil.station.config import EXAMPLE, load_config

    spec = get_robot("ur10e")
    config = load_config(EXAMPLE)
    box = (np.array(config.keep_in["min"], float), np.array(config.keep_in["max"], float))
    model = Geometry.nominal(spec, smr=(0.0, 0.0, 0.045))
    router = Router(spec, box, model, home=np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0]))
    rng = np.random.default_rng(3)
    poses: list[np.ndarray] = []
    while len(poses) < args.legs + 1:  # poses inside the limits and the box
        q = rng.uniform(spec.lower / 2, spec.upper / 2)
        try:
            router.route(None, q)
        except HilError:  # outside the box: not a pose of a plan
            continue
        poses.append(q)
    best = float("inf")
    straight = detour = unsafe = 0
    for _ in range(args.repeat):
        straight = detour = unsafe = 0
        t0 = time.process_time()
        for a, b in itertools.pairwise(poses):
            try:
                route = router.route(a, b)
            except UnsafePathError:
                unsafe += 1
                continue
            straight += len(route) == 1
            detour += len(route) > 1
        best = min(best, time.process_time() - t0)
    print(f"hil from {sys.path[0]}: {args.legs} legs (UR10e, the example's keep-in box): {straight} "
          f"straight, {detour} by a detour, {unsafe} with no safe way; {best / args.legs * 1e3:.2f} ms CPU "
          f"per leg (best of {args.repeat})")


if __name__ == "__main__":
    main()
