"""Was a simulated campaign's warm-up stop right? Its decisions beside the truth's drift still to come.

A `hil calibrate --sim ... --out result.json` result carries the hidden truth (``truth``) and every
reference measurement with the joint temperatures the controller reported (``drift.series``). The
simulated arm's temperature rise is one first-order response with the truth's time constant
(`mocks.heating`: dΔT/dt = (rise·u − ΔT)/τ), and its links grow by 1 + expansion·ΔT (`hil.arm.thermal`),
so the truth knows, at each warm-up check, how much the reference will still move if the arm keeps
cycling: |p(ΔT∞) − p(ΔT_now)|, with ΔT∞ the steady state of the warm-up's cycling, fitted to the
reported temperatures with the truth's own τ (a linear fit: the only unknown is how hard the cycle works
the joints). The bench replays hil's rule (`hil.calibration.warmup_decision.decide_warm`) on the stored
series, check by check, and prints it beside that truth: when the rule stopped (or would stop) and when
the drift still to come really fell under the warm-up's limit. It also says how far the reference
really moved while the arm was measured (from the drift watch's temperatures), the drift the warm-up is
for.

The replay takes the tracker's positions as measured (the campaign also takes out what the joint
readings explain; every visit approaches the reference the same way, so that is micrometres' noise).

Run: python bench/warmup_stop.py result.json [--limit 10e-6]
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.warmup_decision import decide_warm
from mocks.ur.arm import AMBIENT_TEMPERATURE


def true_steady_rise(times: np.ndarray, rise: np.ndarray, tau: float) -> float:
    """ΔT∞ of a first-order response with the known `tau` through the series (least squares on
    a + b·exp(−t/τ); a is ΔT∞)."""
    A = np.column_stack([np.ones_like(times), np.exp(-(times - times[0]) / tau)])
    coef, *_ = np.linalg.lstsq(A, rise, rcond=None)
    return float(coef[0])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("result", help="a hil calibrate --sim result (hil-result/1 with its truth)")
    ap.add_argument("--limit", type=float, default=None, help="m; default: the result's warmup.limit")
    args = ap.parse_args()
    with open(args.result, encoding="utf-8") as f:
        doc = json.load(f)
    truth = Geometry.from_dict(doc["truth"], "truth")
    if truth.thermal is None:
        raise SystemExit("the truth has no thermal block: nothing warms up")
    drift = doc["drift"]
    limit = float(args.limit if args.limit is not None else drift["warmup"]["limit"])
    series = [s for s in drift["series"] if s["phase"] == "warmup" and s["run"] == 1]
    watched = [s for s in drift["series"] if s["phase"] == "drift" and s["run"] == 1]
    t = np.array([s["elapsed"] for s in series])
    xyz = np.array([s["xyz"] for s in series])
    temps = np.array([s["temperatures"] for s in series], dtype=float)
    rise = temps.mean(axis=1) - AMBIENT_TEMPERATURE
    tau = truth.thermal.time_constant
    steady = true_steady_rise(t, rise, tau)
    q = np.array(series[-1]["q"], dtype=float)

    def point(dT: float) -> np.ndarray:
        return Kinematics(truth.grown(dT)).points(q[None, :])[0]

    per_kelvin = float(np.linalg.norm(point(1.0) - point(0.0)))
    left = np.array([np.linalg.norm(point(steady) - point(r)) for r in rise])
    print(f"truth: τ {tau:.0f} s, rise {truth.thermal.rise:g} K for an arm moving all the time; the "
          f"warm-up's cycling heads for ΔT∞ {steady:.2f} K (fitted with the truth's τ); the reference "
          f"moves {per_kelvin * 1e6:.1f} µm/K; limit {limit * 1e6:.1f} µm")
    print(" k  min    ΔT/K  true left/µm  fit τ/s (upper, from)   left/µm (upper)  span/min  flat  verdict")
    stop_rule = stop_truth = None
    for k in range(1, len(t) + 1):
        d = decide_warm(t[:k], xyz[:k] - xyz[0], limit, temperatures=temps[:k])
        f = d.fit
        fit = ("-" if f is None else f"{f.time_constant:6.0f} ({f.time_constant_upper:6.0f}, "
               f"{f.source[:5]})")
        ahead = "-" if f is None else f"{f.remaining * 1e6:6.1f} ({f.remaining_upper * 1e6:6.1f})"
        print(f"{k:2d} {(t[k - 1] - t[0]) / 60:5.1f} {rise[k - 1]:6.2f} {left[k - 1] * 1e6:12.1f}  "
              f"{fit:>24}  {ahead:>16}  {d.span / 60:7.1f}  {str(d.flat)[:5]:5s} {d.rule or '-'}")
        if d.warm and stop_rule is None:
            stop_rule = k - 1
        if left[k - 1] < limit and stop_truth is None:
            stop_truth = k - 1
    ran = drift["warmup"]
    print(f"the campaign: warm-up {ran['seconds'] / 60:.1f} min, converged {ran['converged']}, "
          f"{len(series)} references, rule {ran.get('rule') or '(not recorded)'}")
    if stop_rule is not None:
        print(f"the rule calls it warm at check {stop_rule + 1} ({(t[stop_rule] - t[0]) / 60:.1f} min), "
              f"with {left[stop_rule] * 1e6:.1f} µm still to come in truth")
    else:
        print("the rule never calls it warm on this series")
    if stop_truth is not None:
        print(f"the truth's drift still to come first fell under the limit at check {stop_truth + 1} "
              f"({(t[stop_truth] - t[0]) / 60:.1f} min)")
    if watched:
        base = next((s for s in drift["series"] if s["baseline"]), series[-1])
        base_rise = float(np.mean(base["temperatures"])) - AMBIENT_TEMPERATURE
        rises = np.array([np.mean(s["temperatures"]) - AMBIENT_TEMPERATURE for s in watched])
        moved = [np.linalg.norm(point(r) - point(base_rise)) for r in rises]
        print(f"while measuring: ΔT {rises.min():.2f}..{rises.max():.2f} K against {base_rise:.2f} K at the "
              f"baseline; the reference's true thermal drift from the baseline at most "
              f"{max(moved) * 1e6:.1f} µm (the drift watch measured at most "
              f"{(drift['max'] or 0.0) * 1e6:.1f} µm, limit {drift['limit'] * 1e6:.1f} µm)")


if __name__ == "__main__":
    main()
