"""Reusing a pose choice on every robot of a line (``campaign.plan_cache``).

An end-of-line cell calibrates robot after robot of one type, on one fixture, with the tracker where
it always stands: every campaign asks the chooser the same question. The time-aware search spends
``campaign.search_time`` seconds (and the candidates and method 000's reference some more) before the
first move, and, being a time-limited search, answers a little differently each time. With a cache
directory the first campaign's choice is written there and every later campaign with the same question
reuses it: the selection compute is paid once per station layout, and every robot of the line is
measured on the same poses, so their results compare pose for pose.

The question is the `SelectionRequest` (role, count, seed, the nominal model with the tracker pose (to
1 cm and 0.01 rad: a bootstrapped tracker moves a little every campaign) and the SMR (to 1 mm), keep-in
box, acceptance angle, index, candidates, the poses to exclude or visit, and where the arm starts, to
0.01 rad) and every configuration value the choice depends on (the robot's type and motion,
payload and mounting; the tracker's protocol, position and measuring time; the SMR; the keep-in box; the
campaign section), plus hil's version: a new hil may choose differently. Connection details (addresses,
serial settings) and the weather are not part of it. A key is a SHA-256 of that canonical JSON; the entry
is ``<key>.json`` (the poses and the chooser's info), written atomically. An entry that cannot be read
is chosen again and rewritten, with a warning: the cache only ever saves time.

Written here: no library caches a numpy-returning function on disk under a key hil must define anyway.
"""

from __future__ import annotations

import hashlib
import json
import logging
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from hil.campaign.events import jsonable
from hil.errors import InputError
from hil.files.outputs import atomic_write_text

log = logging.getLogger(__name__)

FORMAT = "hil-plan-cache/1"

#: Configuration values a choice depends on, by section (None: the whole section).
KEYED: dict[str, tuple[str, ...] | None] = {
    "robot": ("type", "speed", "acceleration", "settle", "settle_time", "settle_max", "joint_samples",
              "payload", "mounting"),
    "tracker": ("protocol", "position", "measure_time"),
    "smr": None,
    "keep_in": None,
    "campaign": None,
}

#: Start poses this close (rad, every joint) ask the same question: the first move differs by a few ms.
START_RESOLUTION = 0.01

#: A tracker located by the bootstrap lands a little elsewhere every campaign (about a centimetre with
#: the SMR fitted too, `hil.campaign.calibration_plan`): positions to 1 cm and orientations to 0.01 rad ask
#: the same question. The chooser keeps `ACCEPTANCE_MARGIN_DEG` (5°) of the SMR's cone in reserve for exactly
#: that, and 1 cm at the 2-4 m of a station turns the line of sight by under 0.3°; the engine checks the
#: line of sight again before every pose anyway.
TRACKER_RESOLUTION = 0.01
ROTATION_RESOLUTION = 0.01
SMR_RESOLUTION = 0.001


def request_key(config: Any, request: Any) -> str:
    """The cache key of `request` under `config` (module docstring)."""
    from hil import __version__

    values = config.as_dict()
    keyed = {section: {k: v for k, v in values[section].items() if (keys is None or k in keys)
                       and k != "plan_cache"} for section, keys in KEYED.items()}
    model = request.model
    start = None if request.start is None else np.round(np.asarray(request.start, float) / START_RESOLUTION)
    question = {
        "hil": __version__, "config": keyed, "role": request.role, "count": int(request.count),
        "seed": int(request.seed), "index": request.index, "candidates": int(request.candidates),
        "acceptance_angle": float(request.acceptance_angle),
        "model": {"robot": model.robot, "smr": _quantised(model.smr, SMR_RESOLUTION),
                  "tracker": _quantised(model.tracker.translation, TRACKER_RESOLUTION),
                  "tracker_rotation": _quantised(pin.log3(model.tracker.rotation), ROTATION_RESOLUTION)},
        "keep_in": [_rounded(b) for b in request.keep_in],
        "exclude": _rounded(request.exclude),
        "fixed": None if request.fixed is None else _rounded(request.fixed),
        "start": None if start is None else start.astype(int).tolist(),
    }
    text = json.dumps(question, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def _quantised(a: Any, step: float) -> list[int]:
    return np.round(np.asarray(a, dtype=float).ravel() / step).astype(int).tolist()


def _rounded(a: Any) -> Any:
    """Floats to 12 significant digits: the same value computed twice hashes alike."""
    return [float(f"{v:.12g}") for v in np.asarray(a, dtype=float).ravel()]


def cache_directory(directory: str | Path) -> Path:
    """The cache directory, created if need be; InputError (one line) when it cannot be."""
    root = Path(directory).expanduser()
    try:
        root.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(f"campaign.plan_cache: cannot create {root}: {exc.strerror or exc}") from None
    if not root.is_dir():
        raise InputError(f"campaign.plan_cache: {root} is not a directory")
    return root


def cached_chooser(choose: Any, config: Any, directory: str | Path) -> Any:
    """`choose` (a `ChoosePoses`) answering from ``directory`` when it answered the same question before."""
    from hil.campaign.calibration_plan import Choice

    root = cache_directory(directory)

    def cached(request: Any) -> Any:
        key = request_key(config, request)
        path = root / f"{key}.json"
        if path.exists():
            try:
                doc = json.loads(path.read_text())
                if doc.get("format") != FORMAT:
                    raise ValueError(f"format {doc.get('format')!r}, expected {FORMAT}")
                poses = np.asarray(doc["poses"], dtype=float).reshape(-1, 6)
                info = dict(doc["info"]) | {"plan_cache": {"key": key, "reused": True}}
                return Choice(poses, info)
            except (OSError, ValueError, KeyError, TypeError) as exc:
                log.warning("plan cache entry %s unreadable (%s): choosing again", path, exc)
        choice = choose(request)
        doc = {"format": FORMAT, "key": key, "role": request.role,
               "poses": np.asarray(choice.poses, dtype=float).tolist(), "info": jsonable(choice.info)}
        try:
            atomic_write_text(path, json.dumps(doc))
        except OSError as exc:  # the campaign goes on; only the next one will choose again
            log.warning("could not write the plan cache entry %s: %s", path, exc)
        return Choice(choice.poses, dict(choice.info) | {"plan_cache": {"key": key, "reused": False}})

    cached.hidden = getattr(choose, "hidden", None)  # type: ignore[attr-defined]
    return cached
