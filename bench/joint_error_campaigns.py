"""Simulated campaigns with and without the joint-angle harmonics: ``campaign.joint_errors`` none vs auto.

Run from the repository root: ``PYTHONPATH=. python bench/joint_error_campaigns.py [--seeds 1-5]
[--speed 20]``. For each seed, the same campaign as ``hil calibrate --sim --speed 20 --no-warmup --seed
S`` (the realistic simulated UR5e, its warm-up off, on the paced station clock) runs twice, with
``campaign.joint_errors`` set to ``none`` (geometry and compliance) and to ``auto`` (the default: the
terms cross-validation keeps), each in a store of its own. The table prints each run's status, its
validation RMS and its cross-validated RMS (mm), and the means; `hil calibrate` has no option for the
key with ``--sim``, so the bench sets it as the station's configuration override.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from hil.jobs.calibration import CalibrationRequest, calibrate
from hil.jobs.station import StationSource


def seeds(text: str) -> list[int]:
    """``1-5`` or ``1,3,4``."""
    if "-" in text:
        first, last = (int(v) for v in text.split("-"))
        return list(range(first, last + 1))
    return [int(v) for v in text.split(",")]


def run(seed: int, mode: str, speed: float, folder: Path) -> tuple[str, float, float]:
    """(status, validation RMS, cross-validated RMS) of one campaign (m)."""
    source = StationSource.of(config=None, sim=True, speed=speed, seed=seed,
                              overrides={"campaign__joint_errors": mode})
    out = calibrate(CalibrationRequest(source, db=str(folder / f"{mode}-{seed}.db"), no_warmup=True))
    doc = out.document or {}
    validation = (doc.get("validation") or {}).get("after") or {}
    cv = ((doc.get("cross_validation") or {}).get("calibrated") or {})
    return out.status, float(validation.get("rms", float("nan"))), float(cv.get("rms", float("nan")))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=seeds, default=seeds("1-5"))
    ap.add_argument("--speed", type=float, default=20.0)
    args = ap.parse_args()
    started = time.monotonic()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for seed in args.seeds:
            for mode in ("none", "auto"):
                rows.append((seed, mode, *run(seed, mode, args.speed, Path(tmp))))
    print(f"campaign.joint_errors none vs auto, realistic UR5e, --speed {args.speed:g} --no-warmup (mm)")
    print(f"{'seed':>4}  {'mode':<5} {'status':<9} {'validation':>10} {'cross-val.':>10}")
    for seed, mode, status, rms, cv in rows:
        print(f"{seed:>4}  {mode:<5} {status:<9} {rms * 1e3:>10.4f} {cv * 1e3:>10.4f}")
    for mode in ("none", "auto"):
        vals = [r[3] for r in rows if r[1] == mode]
        print(f"mean {mode:<5} validation {sum(vals) / len(vals) * 1e3:.4f}")
    print(f"{time.monotonic() - started:.0f} s")


if __name__ == "__main__":
    main()
