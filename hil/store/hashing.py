"""How a campaign is recognised again: hashes of its station configuration.

A re-run of ``hil calibrate`` finds the campaign it resumes by these hashes (`hil.store.core`), and
the content hashes of models and validations use `canonical_json`. The Alembic migrations that fill
these columns for existing rows import them from here, so they must stay stable: changing what a hash
covers needs a migration recomputing the column.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from typing import Any


def canonical_json(value: Any) -> str:
    """Deterministic compact JSON (sorted keys): equal values give equal text, hence equal hashes."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False)


def config_hash(config: Mapping[str, Any]) -> str:
    """sha256 of a station configuration, which is how a re-run finds the campaign it resumes.

    The ``store`` section is left out: where the results are kept does not change what is being
    calibrated, and moving the database must not orphan an unfinished campaign.
    """
    body = {k: v for k, v in config.items() if k != "store"}
    return hashlib.sha256(canonical_json(body).encode()).hexdigest()


# What does not change what a campaign measures, so a re-run that differs only there resumes it:
# how hil reaches the devices and how long it waits for them. ``None`` drops the whole section.
#   robot.address   — the arm is identified by its serial, which `find_resumable` matches instead
#                     (and, when the serial is unknown, it compares the address itself);
#   tracker.url     — a serial port renamed (/dev/ttyUSB0 -> /dev/ttyUSB1), a socket:// or tcp:// address
#                     changed: the same instrument on another cable or network;
#   tracker.baudrate, tracker.parity — settings of that cable, not of the measurement;
#   tracker.timeout, tracker.warmup, timeouts.* — how long to wait for a reply, a warm laser, a
#                     move, a relock: a longer wait measures the same point (a skipped pose is
#                     recorded as skipped, not measured differently);
#   store.*         — where the results are kept;
#   verify.*        — the ISO 9283 test's cube and cycles, which a calibration never uses (a
#                     verification carries them in an identity block of its own, `hil.verify.session`);
#                     stored configurations from before the section existed have none, so no stored
#                     hash changes;
#   warmup.*, drift.* — how long the arm is warmed up before measuring and how often a reference pose
#                     is re-measured: the same poses are measured (a resumed run warms up again
#                     anyway); dropped whole, like verify, so no stored hash changes either.
# Everything else stays: the robot type and motion settings, the tracker's protocol (GeoCOM and emScon
# measure differently: a stationary measuring time, a reflector choice), its position guess and the
# atmospheric correction (which change every distance), the SMR, the keep-in box, the campaign's
# counts, seed and acceptance. A value starting with ``sim:`` is kept even in a dropped key: the
# simulated station identifies itself there by what it simulates (seed, truth), not where it listens.
# Changing this table changes the hashes: it needs a new migration recomputing ``measure_hash``.
MEASUREMENT_IGNORED: Mapping[str, tuple[str, ...] | None] = {
    "robot": ("address",),
    "tracker": ("url", "baudrate", "parity", "timeout", "warmup"),
    "timeouts": None,
    "store": None,
    "verify": None,
    "warmup": None,
    "drift": None,
}


def measurement_identity(config: Mapping[str, Any]) -> dict[str, Any]:
    """The station configuration without what does not change the measurement (`MEASUREMENT_IGNORED`)."""
    body: dict[str, Any] = {}
    for section, values in config.items():
        if section in MEASUREMENT_IGNORED and MEASUREMENT_IGNORED[section] is None:
            continue
        dropped = MEASUREMENT_IGNORED.get(section) or ()
        if isinstance(values, Mapping):
            values = {k: v for k, v in values.items()
                      if k not in dropped or (isinstance(v, str) and v.startswith("sim:"))}
        body[section] = values
    return body


def measurement_hash(config: Mapping[str, Any]) -> str:
    """sha256 of `measurement_identity`: how a re-run finds the campaign it resumes, so the poses
    already measured are reused when only a connection address, a timeout or the store changed."""
    return hashlib.sha256(canonical_json(measurement_identity(config)).encode()).hexdigest()
