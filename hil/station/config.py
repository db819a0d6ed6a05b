"""Station configuration (TOML): what the campaign needs to know about one cell.

Every key is declared once below with its type, default and check, so the error for a wrong value
names the key (``station.toml: robot.speed: must be in (0, 3.14] rad/s, got -1``) and an unknown key is
refused rather than silently ignored (a typo in ``acceptance`` must not pass a bad robot). Every
number has a physical range (its unit and where the limit comes from are in a comment by the key), so
a value typed in the wrong unit or an absurd one is refused when the file is read, before a database
is created or the arm moves. A commented example lives in ``hil/station/station.example.toml``.
"""

from __future__ import annotations

import ipaddress
import os
import re
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hil.arm.catalog import get_robot
from hil.errors import InputError
from hil.files.inputs import MAX_CONFIG_BYTES, read_input_text
from hil.files.quantities import check_vector, quantity
from hil.station.store_url import store_url_problem

EXAMPLE = Path(__file__).with_name("station.example.toml")
PROTOCOLS = ("geocom", "emscon")


@dataclass(frozen=True)
class Key:
    """One declared configuration key."""

    kind: str  # "str", "float", "int", "bool", "vec3", "str?", "vec3?"
    default: Any
    check: Callable[[Any], str | None] | None = None  # returns an error text or None
    help: str = ""


#: The URL schemes each tracker protocol speaks (drivers.tracker.geocom.transport: pyserial's
#: serial_for_url; drivers.tracker.emscon.transport: TCP). A plain path is a serial device (GeoCOM).
TRACKER_SCHEMES: dict[str, tuple[str, ...]] = {
    "geocom": ("socket", "rfc2217", "spy"),
    "emscon": ("tcp", "socket"),
}


#: How a simulated station's tracker is named in its campaign identity (``sim:seed=…;truth=…``): the
#: identity is hashed, never connected to, whatever the protocol.
SIMULATED_IDENTITY = "sim:"


def tracker_url_problem(url: str, protocol: str) -> str | None:
    """Why `url` cannot reach a `protocol` tracker, or None: checked with the rest of the config, so a
    URL hil does not speak (``http://``), a port out of range or a missing host is bad input naming
    tracker.url, not a hardware fault after a connection was tried."""
    if not url:
        return None  # required only where a campaign runs (`check_runnable`)
    if url.startswith(SIMULATED_IDENTITY):
        return None  # a simulated station's identity (`hil.station.simulated`), never connected to
    if "://" not in url:
        if protocol == "emscon":
            return f"an emScon tracker is reached by tcp://host[:port], got {url!r}"
        return None if url.strip() == url and "\x00" not in url else f"not a serial device path: {url!r}"
    scheme, rest = url.split("://", 1)
    known = TRACKER_SCHEMES.get(protocol, ())
    if scheme.lower() not in known:
        return (f"{scheme}:// is not a URL a {protocol} tracker speaks; use "
                + ("a serial device path or " if protocol == "geocom" else "")
                + ", ".join(f"{k}://" for k in known))
    if scheme.lower() == "spy":  # pyserial's logging wrapper around another port: spy://PORT?file=log
        inner = rest.split("?", 1)[0]
        if not inner:
            return "spy:// wraps a port: spy:///dev/ttyUSB0 or spy://socket://host:port"
        return tracker_url_problem(inner, protocol) if "://" in inner else None
    netloc = rest.split("/", 1)[0].split("?", 1)[0]
    host, colon, port = netloc.rpartition(":") if ":" in netloc else (netloc, "", "")
    if not host:
        return f"{url!r} names no host: {scheme}://host:port"
    if not colon:
        if protocol == "emscon":  # emScon's TPI port, 700, when none is given (its transport)
            return _host(host)
        return f"{url!r} names no port: {scheme}://host:port"
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        return f"port {port!r} of {url!r} is not a TCP port (1 to 65535)"
    return _host(host.strip("[]"))


def _plan_cache(value: Any) -> str | None:
    """A directory path, or "" (off); whether it can be created is checked when the campaign starts."""
    if not isinstance(value, str):
        return f"must be a directory path (a string), got {value!r}"
    if "\x00" in value or (value and not value.strip()):
        return f"must be a directory path or \"\" (off), got {value!r}"
    return None


def _quantity(name: str, *, off: float | None = None) -> Callable[[Any], str | None]:
    """A check that a number is a value of the quantity `name` (`hil.files.quantities`: its unit,
    range and source are there, the same row the command line's options use); `off` is a value outside
    the range that means "none" (``time_budget = 0``)."""
    row = quantity(name)

    def check(v: Any) -> str | None:
        if off is not None and v == off:
            return None
        try:
            return row.problem(float(v))
        except OverflowError:  # an integer of hundreds of digits
            return f"expected a finite number in {row.span()}, got an integer of {len(str(abs(v)))} digits"

    return check


def _vector(name: str, *, norm: bool = False) -> Callable[[Any], str | None]:
    """A check that every coordinate (or, with `norm`, the length) of a vector is of quantity `name`."""

    row = quantity(name)

    def check(v: Any) -> str | None:
        if norm:
            try:
                check_vector(v, name, "", norm=True)
            except InputError as exc:
                return str(exc).removeprefix(": ")
            return None
        return next((f"coordinate {i + 1}: {why}" for i, x in enumerate(v)
                     if (why := row.problem(float(x))) is not None), None)

    return check


# Host names as RFC 1123 allows them: dot-separated labels of letters, digits and inner hyphens, at most
# 63 characters each; the last label is not all digits (RFC 3696 §2), so 127.0.0.256 is not a name.
_LABEL = re.compile(r"[A-Za-z0-9](?:[A-Za-z0-9-]{0,61}[A-Za-z0-9])?")


def _host(v: Any) -> str | None:
    """An IP address or a host name: "not an address" failed only at connect, as a hardware fault
    (exit 3) after the store was written; a typo in the address is bad input."""
    try:
        ipaddress.ip_address(v)
        return None
    except ValueError:
        pass
    labels = v[:-1].split(".") if v.endswith(".") else v.split(".")
    if (0 < len(v) <= 253 and all(_LABEL.fullmatch(label) for label in labels)
            and not labels[-1].isdigit()):
        return None
    return f"must be an IP address or a host name, got {v!r}"


def _name(v: Any) -> str | None:
    """A station name: shown in reports and in ``hil history``'s 80-column table."""
    ok = 0 < len(v) <= 64 and v.isprintable() and v.strip() == v
    return None if ok else f"must be 1 to 64 printable characters without surrounding spaces, got {v!r}"


#: The ceilings other modules name (each the high end of its row in `hil.files.quantities`).
MAX_ACCEPTANCE = quantity("rms threshold").high
MAX_CANDIDATES = int(quantity("candidates").high)
MAX_POSES = int(quantity("pose count").high)


def _robot(v: Any) -> str | None:
    try:
        get_robot(v)
    except InputError as exc:
        return str(exc)
    return None


def _index(v: Any) -> str | None:
    return None if v in ("O1", "O2", "O3", "O4", "O5") else f"must be one of O1..O5, got {v!r}"


#: `campaign.selection` values: method 000 then the tour, or poses and tour together.
SELECTIONS = ("tabu", "time-aware")


def _selection(v: Any) -> str | None:
    return None if v in SELECTIONS else f"must be one of {', '.join(SELECTIONS)}, got {v!r}"


#: `campaign.mode` values: stop at every pose and measure it still, or sweep through the poses while
#: both instruments stream (docs/design.md, The calibration campaign: the sweep mode).
MODES = ("stop-and-go", "sweep")


def _mode(v: Any) -> str | None:
    return None if v in MODES else f"must be one of {', '.join(MODES)}, got {v!r}"


def sweep_refused(protocol: str) -> str | None:
    """Why a tracker speaking `protocol` cannot sweep, or None. GeoCOM is a polled RPC: a motorised
    total station's tracking mode gives about 10 distances a second (Leica TPS1200 user manual,
    ≈0.15 s per distance; docs/design.md, Facts: GeoCOM), a hundredth of emScon's continuous 1000 Hz
    (Leica AT960 datasheet, Facts: two clocks), and its readings carry no instrument stamp: at 0.25 m/s
    the SMR moves 25 mm between two of them."""
    if protocol == "geocom":
        return ("GeoCOM cannot stream fast enough: a polled reading takes about 0.15 s (about 10 a "
                "second, Leica TPS1200) and carries no instrument time stamp; a sweep needs emScon's "
                "continuous mode (tracker.protocol = \"emscon\")")
    return None


def _protocol(v: Any) -> str | None:
    return None if v in PROTOCOLS else f"must be one of {', '.join(PROTOCOLS)}, got {v!r}"


#: How a pose visit waits for the arm to be still before it measures (`hil.campaign.steps.acquire`).
SETTLE_MODES = ("stable", "fixed")


def _settle(v: Any) -> str | None:
    return None if v in SETTLE_MODES else f"must be one of {', '.join(SETTLE_MODES)}, got {v!r}"


def _joint_errors(v: Any) -> str | None:
    """none, auto or harmonic orders (`hil.calibration.joint_error_request.parse_request`)."""
    from hil.calibration.joint_error_request import parse_request

    if not isinstance(v, str):
        return f"must be a string (none, auto or orders such as \"1,2\"), got {v!r}"
    try:
        parse_request(v, "value")
    except InputError as exc:
        return str(exc).removeprefix("value: ")
    return None


#: Every parameter of the kinematic model (`hil.arm.kinematics.N_PARAMETERS`: a 6-D placement per joint
#: and of the flange, the SMR offset, the tracker pose), of which a subset is identifiable: this many
#: poses' worth always suffices, so a config asking for that many needs no kinematics (pinocchio) to
#: be checked — reading a configuration stays cheap for ``hil history --config``.
_ALL_PARAMETERS = 6 * 6 + 6 + 3 + 6


def minimum_calibration_poses(robot: str, compliance: bool = False, payload: Any = None,
                              gravity: Any = None) -> tuple[int, int]:
    """(fewest calibration poses, identifiable parameters) of `robot`: the fit identifies the
    parameters from 3 coordinates per pose and keeps 3 to spare (`selector.design.minimum_poses`, the
    rule the selector and the fit apply), so fewer would fail only after the bootstrap moved the arm.
    With `compliance` the joints' identifiable compliances (for this payload and gravity) count too."""
    from hil.arm.kinematics import identifiable_parameters, identifiable_with_compliance
    from selector.design import minimum_poses

    if compliance:
        n = len(identifiable_with_compliance(robot, payload, gravity))
    else:
        n = len(identifiable_parameters(robot))
    return minimum_poses(n), n


def _parity(v: Any) -> str | None:
    return None if v in ("N", "E", "O", "M", "S") else f"must be one of N, E, O, M, S, got {v!r}"


SCHEMA: dict[str, dict[str, Key]] = {
    "station": {
        "name": Key("str", "station", _name, "a name for reports and the history"),
    },
    "robot": {
        "type": Key("str", "ur5e", _robot),
        "address": Key("str", "127.0.0.1", _host, "the controller's IP address or host name"),
        # ur_rtde's moveJ takes at most 3.14 rad/s and 40 rad/s² (UR_JOINT_VELOCITY_MAX and
        # UR_JOINT_ACCELERATION_MAX), the driver's own RobotConfig check: more was exit 70 at connect
        "speed": Key("float", 0.5, _quantity("joint speed"), "joint speed of moves (rad/s)"),
        "acceleration": Key("float", 1.0, _quantity("joint acceleration"),
                            "joint acceleration of moves (rad/s²)"),
        # a UR arm is steady within a fraction of a second of arriving; a minute per pose is a value
        # typed in milliseconds
        "settle_time": Key("float", 0.3, _quantity("settle time"), "wait after the arm is steady (s)"),
        # "stable": measure as soon as the tracker's last readings agree within campaign.stability (the
        # arm's ring has died out), the joints read in the same window; "fixed": wait settle_time, then
        # read the joints, then measure (hil.campaign.steps.SettleMeasure)
        "settle": Key("str", "stable", _settle, "stable (settle on the tracker's evidence) or fixed "
                                                 "(wait settle_time)"),
        # a UR's ring dies out within a second or two (mocks.ringing); a minute still ringing is a fault
        # (a loose SMR nest, a vibrating floor), not a wait
        "settle_max": Key("float", 5.0, _quantity("settle limit"),
                          "stable: longest wait for steady readings before the point is unstable (s)"),
        # joint readings come at the RTDE rate (500 Hz e-Series, 125 Hz CB3): 1000 are 2-8 s per pose,
        # already far past what averaging the encoders' noise gains
        "joint_samples": Key("int", 10, _quantity("joint samples"), "joint readings averaged per pose"),
        # what the arm carries during the campaign (Polyscope's Payload: mass and centre of mass in the
        # flange frame); a compliant arm sags by compliance x the gravity torque, so the model needs it
        "payload": Key("payload?", None, help="{mass = kg, com = [x, y, z]} in the flange frame (m)"),
        # roll, pitch, yaw (rad) of the base in the world (Polyscope's Mounting tilt and rotation): a
        # floor arm is [0, 0, 0], a ceiling arm [3.14159, 0, 0]; gravity is turned with it
        "mounting": Key("vec3", (0.0, 0.0, 0.0), _vector("mounting angle"),
                        "base orientation in the world (rpy, rad)"),
    },
    "tracker": {
        "protocol": Key("str", "geocom", _protocol,
                        "geocom (GeoCOM on a serial line) or emscon (Leica emScon TPI over TCP)"),
        "url": Key("str", "", help="geocom: serial device or socket://, rfc2217://, spy:// URL; "
                                   "emscon: tcp://host:700"),
        # RS-232 rates: GeoCOM instruments run at 2400-115200 baud, USB adapters up to 921600
        "baudrate": Key("int", 115200, _quantity("baud rate")),
        "parity": Key("str", "N", _parity),
        # a GeoCOM/emScon reply takes milliseconds, a measurement with a search seconds: beyond five
        # minutes a dead link would go unnoticed
        "timeout": Key("float", 3.0, _quantity("reply timeout"), "reply timeout (s)"),
        "position": Key("vec3?", None, _vector("tracker distance from the base", norm=True),
                        "approximate position in the robot base frame (m)"),
        # the atmospheric correction of the laser's wavelength is meant for the air the tracker works in:
        # Leica's trackers operate within -15..+45 °C (AT403, the widest), at most 5500 m above sea level
        # (about 500 hPa; the sea-level record is 1084 hPa); humidity is relative, 0-100 %
        "temperature": Key("float", 20.0, _quantity("air temperature"),
                           "air temperature (°C) for the atmospheric correction"),
        "pressure": Key("float", 1013.25, _quantity("air pressure"), "air pressure (hPa)"),
        "humidity": Key("float", 50.0, _quantity("relative humidity"), "relative humidity (%)"),
        "reflector": Key("str", "", help="emscon: reflector name as the tracker lists it (empty: keep the "
                                         "tracker's current one)"),
        # a stationary measurement averages for a fraction of a second to a few seconds
        "measure_time": Key("float", 0.5, _quantity("measure time"),
                            "emscon: stationary measuring time per sample (s)"),
        "bird_bath": Key("bool", False, help="emscon: after a failed search for the SMR, send the beam to "
                                             "the bird bath for an operator to catch"),
        # a cold AT9xx laser is ready within minutes; two hours without it is a fault, not a cold start
        "warmup": Key("float", 0.0, _quantity("laser warm-up"),
                      "emscon: longest wait at connect for the laser to warm up (s); then the run waits"),
    },
    "smr": {
        "offset": Key("vec3", (0.0, 0.0, 0.045), _vector("smr offset", norm=True),
                      "SMR centre guess in the flange frame (m)"),
        "acceptance_angle": Key("float", 30.0, _quantity("acceptance angle"),
                                "SMR acceptance half-angle (degrees)"),
    },
    "keep_in": {
        "min": Key("vec3", (-2.0, -2.0, 0.0), _vector("keep-in corner"),
                   "keep-in box corner (robot base frame, m)"),
        "max": Key("vec3", (2.0, 2.0, 2.0), _vector("keep-in corner")),
    },
    "campaign": {
        # the fewest calibration poses depend on the robot (checked below, with robot.type)
        "calibration_poses": Key("int", 30, _quantity("pose count")),
        "validation_poses": Key("int", 20, _quantity("pose count")),
        # 0: validation poses are a simple random sample of the candidates; k > 0: a two-stage cluster
        # sample (selector.cluster_sample), k clusters of nearby poses drawn PPS, validation_poses / k
        # in each: still an unbiased sample of the workspace, in less robot time (checked below: k must
        # divide validation_poses)
        "validation_clusters": Key("int", 0, _quantity("pose count or none"),
                                   "clustered validation: clusters drawn (0: simple random sample)"),
        # the bootstrap has 8 arm moves (hil.campaign.calibration_plan._BOOTSTRAP_DELTAS) and makes at
        # least 4: other values were silently clamped
        # plus 4 turns of the wrist (_WRIST_TURNS), which make the SMR's offset observable: 6 measures 10
        "bootstrap_poses": Key("int", 6, _quantity("bootstrap poses"),
                               "small arm moves measured to locate the tracker (4 wrist turns are added)"),
        # each sample is a tracker measurement (~0.1-1 s): 100 per point already averages the noise away
        "samples": Key("int", 5, _quantity("samples"), "tracker samples per point"),
        # a tracker's noise is micrometres (AT960: 15 µm + 6 µm/m MPE): a spread allowed above 1 mm no
        # longer says the SMR was still, and 10 (m) is a value in micrometres
        "stability": Key("float", 50e-6, _quantity("point spread"),
                         "largest per-axis spread of a point (m)"),
        # unset: the automatic verdict (hil.campaign.acceptance): better than the nominal and the
        # controller's model by cross-validation, validation within a factor of the cross-validated RMS
        # and within the robot class's bound; set: validation RMS at most this (and still better)
        "acceptance": Key("float?", None, _quantity("rms threshold"),
                          "validation RMS threshold (m); unset: judged by cross-validation and the "
                          "robot class's bound"),
        "index": Key("str", "O1", _index, "observability index for pose selection"),
        # method 000 (tabu, the seed's) chooses calibration_poses poses, then their order; time-aware
        # chooses poses and order together for robot time (hil.calibration.timed_selection): the
        # predicted accuracy of method 000's calibration_poses, or the best within time_budget
        "selection": Key("str", "tabu", _selection, "pose selection: tabu (method 000) or time-aware"),
        # stop-and-go measures each pose standing still; sweep follows a smooth path through the
        # calibration poses while the tracker (emScon only) and the joints stream (hil.campaign.sweep)
        "mode": Key("str", "stop-and-go", _mode, "campaign mode: stop-and-go or sweep (emScon only)"),
        # unset: a sweep moves within robot.speed and robot.acceleration, as stop-and-go's moves; set: at
        # this tool speed (each joint at most it over the reach) and within the deflection model's
        # quasi-static acceleration (hil.campaign.sweep_plan.sweep_limits; bench/sweep_time.py's rule)
        "sweep_speed": Key("float?", None, _quantity("sweep tool speed"),
                           "sweep: tool speed (m/s); unset: robot.speed and robot.acceleration"),
        # a campaign of 10 poses takes about a minute of robot time; a day is a value in milliseconds
        "time_budget": Key("float", 0.0, _quantity("time budget", off=0),
                           "time-aware: robot seconds for the calibration and validation tour "
                           "(0: reach method 000's accuracy in the least time)"),
        # the time-aware search improves its tour for this long before the campaign moves (ruin and
        # recreate, selector.time_aware): bench/cycle_time.py shows the robot time still falling by
        # ~1 % from 10 to 20 s; an hour is a value in the wrong unit
        "search_time": Key("float", 10.0, _quantity("search time"),
                           "time-aware: seconds the search improves the tour before the first move"),
        # an end-of-line cell asks the same question robot after robot (hil.campaign.plan_cache): the
        # first campaign's poses are kept there and reused, so the search is paid once per layout
        "plan_cache": Key("str", "", _plan_cache, "directory keeping pose choices for reuse by later "
                                                  "campaigns asking the same question (\"\": off)"),
        "candidates": Key("int", 20000, _quantity("candidates"), "candidate poses for the selector"),
        # numpy's generators take non-negative seeds (-1 was exit 70 in the simulator); 32 bits suffice
        "seed": Key("int", 1, _quantity("seed")),
        # a UR's strain-wave joints sag by tenths of a millimetre under their own weight and payload
        # (hil.arm.physical): the fit identifies the joints' compliance beside the geometry
        "compliance": Key("bool", True, help="identify the joints' compliance (rad/Nm) with the geometry"),
        # low-order joint-angle errors (hil.calibration.joint_error_selection): "auto" by default, as
        # `hil identify`'s: the poses are chosen to spread every joint's angle for every order the
        # calibration poses can carry (hil.campaign.chooser._design_orders) and cross-validation keeps
        # the terms the data support. Measured on the realistic simulated UR5e (hil calibrate --sim
        # --speed 20 --no-warmup; README, "What a real UR reaches"): the validation RMS fell on most
        # seeds, rose on few; "none" leaves the joints' angle errors in every prediction
        "joint_errors": Key("str", "auto", _joint_errors,
                            "joint-angle harmonics to identify: none, auto (cross-validation chooses) or "
                            "orders such as 1,2"),
        # every pose is approached from below in every joint (hil.campaign.steps.APPROACH: a last leg
        # from this far below it), so each joint's lost motion lags the same way at every pose and the
        # geometry absorbs it; 0 approaches each pose from wherever the arm comes. Above 0.1 rad the leg
        # costs more robot time than any lost motion (a milliradian at most) warrants
        "approach": Key("float", 0.005, _quantity("approach distance"),
                        "approach every pose from this far below it in every joint (0: straight there)"),
        "max_consecutive_lost": Key("int", 3, _quantity("lost in a row"),
                                    "poses in a row that lose the beam before the run stops, saying the "
                                    "tracker position looks wrong"),
        # the stopping rule (hil.campaign.stopping): after each calibration pose, fit the points so far and
        # stop visiting calibration poses once the predicted validation RMS is within stop_margin × the
        # acceptance; the validation poses are still all measured and still give the verdict
        "stop_early": Key("bool", False, help="stop acquiring calibration poses once the fit so far "
                                              "predicts the acceptance with margin"),
        # a fraction of campaign.acceptance: the prediction is an expected RMS, and one campaign's validation
        # RMS scatters about it by up to ~1.4x (99th percentile; hil.campaign.stopping.DEFAULT_MARGIN);
        # 1 trusts the expectation itself
        "stop_margin": Key("float", 0.7, _quantity("fraction"),
                           "stop_early: stop once the predicted validation RMS is at most this fraction "
                           "of the acceptance"),
    },
    # Warm-up before measuring (ISO 9283:1998 §6.2, conditions prior to testing: the robot is warmed up
    # before it is measured; every tracker calibration guide says the same). A UR's joints warm by a few
    # kelvin over the first tens of minutes of motion and its aluminium links grow with them (2.3e-5 /K,
    # `hil.arm.thermal`): a metre of arm grows by about 0.1 mm, the size of the whole acceptance. The run
    # cycles through the planned calibration poses and re-measures a reference pose every `interval`
    # seconds until the first-order fit of those measurements says less than `limit` of drift is still
    # to come (`hil.campaign.warmup`).
    "warmup": {
        "enabled": Key("bool", True, help="warm the arm up before measuring"),
        # a joint's warm-up time constant is about 15 min (`hil.arm.thermal`, τ = 900 s): a check every
        # 2 min gives the fit 7 points per time constant and costs one reference visit (~10 s, plus
        # drift.settle's 2 s and drift.samples' 2 s of GeoCOM readings: about a tenth of the motion);
        # under 10 s is mostly reference visits, and over an hour sees no warm-up at all
        "interval": Key("float", 120.0, _quantity("warm-up interval"),
                        "seconds of cycling motion between reference measurements"),
        # a tenth of the default 0.1 mm acceptance, and a third of the drift watch's limit, so a warm arm
        # does not flag the campaign; a tracker repeats an averaged point to a few µm (AT960: ±(15 µm +
        # 6 µm/m) MPE, typically half), which the fit of the whole series averages further; 1 mm is a value
        # typed in millimetres
        "limit": Key("float", 10e-6, _quantity("point spread"),
                     "warm when the drift still to come (fitted) is below this (m)"),
        # the fit is trusted once its series spans three time constants (95 % of the rise): 45 min for
        # a UR's 15; an hour leaves room for a slower arm, and an arm still drifting after it is drifting
        # for another reason (the tracker's stand, the room): the run goes on, with a warning
        "max_time": Key("float", 3600.0, _quantity("warm-up time"),
                        "longest warm-up (s); then the run measures anyway, with a warning"),
    },
    # Drift watch (ISO 9283:1998 §7.6, drift of pose characteristics): the reference pose is measured
    # again every `every` poses; a campaign whose reference moved more than `limit` from where it was
    # after the warm-up is flagged (it keeps the verdict its validation gives).
    "drift": {
        # every 10 poses is a reference visit per ~2 min of measuring (+10 % time); 0 turns it off
        "every": Key("int", 10, _quantity("pose count or none"),
                     "re-measure the reference after every N poses (0: off)"),
        # 30 % of the default 0.1 mm acceptance: a drift that large is a third of the error budget the
        # calibration is judged on; three times the warm-up limit, so noise alone does not flag a campaign
        "limit": Key("float", 30e-6, _quantity("point spread"),
                     "flag the campaign when the reference moved more than this (m)"),
        # a reference visit (drift watch and warm-up) must see micrometres, while the arm rings after its
        # approach for a while (a lightweight arm's first modes 7-12 Hz, structural damping 2-3.6 %:
        # mocks.ringing's sources), and a window's spread cannot tell an aliased ring from the tracker's
        # noise (a realistic simulated UR5e's drift watch read 9-24 µm of ring with 0.4-5 µm of true drift,
        # docs/design.md, Facts: what a drift watch sees). 2 s still is 3 envelope time constants of a
        # 3.6 %-damped 7 Hz mode (4 % of its ring left; hil's assumption that a UR's servos damp no less)
        "settle": Key("float", 2.0, _quantity("settle time"),
                      "seconds the arm stands still at the reference before it is read"),
        # 20 readings average the tracker's noise by 2 against a pose's 5 and the ring's remainder over
        # a 2 s window (GeoCOM's 0.1 s readings; an emScon point's 0.5 s makes it 10 s)
        "samples": Key("int", 20, _quantity("samples"), "tracker samples per reference measurement"),
    },
    "timeouts": {
        # how long the run waits before calling something lost; the longest move of a UR arm (half a
        # turn of a joint at the slowest useful speed, 0.01 rad/s) takes about five minutes, an operator
        # clearing a protective stop or catching the beam may take a shift (8 h); more is a value in ms
        "connect": Key("float", 10.0, _quantity("short timeout")),
        "move": Key("float", 60.0, _quantity("move timeout")),
        "measure": Key("float", 10.0, _quantity("short timeout")),
        "suspend": Key("float", 600.0, _quantity("operator timeout"),
                       "longest wait for a suspender to clear (s)"),
        "relock": Key("float", 30.0, _quantity("move timeout"),
                      "longest wait for a lost beam before the pose is skipped"),
        # a PostgreSQL server restarted for an update is back within a minute; a network cut may take
        # longer: the arm stands still meanwhile, and past this the run stops, resumable
        "database": Key("float", 600.0, _quantity("operator timeout"),
                        "longest wait for a lost database link before the run stops (s)"),
    },
    "verify": {
        # the ISO 9283 test cube (`hil verify`, `hil calibrate --verify`), in the robot base frame: every
        # UR's reach is within 1.75 m (UR20), so a centre beyond 2 m is a value in millimetres
        "centre": Key("vec3?", None, _vector("cube centre distance", norm=True),
                      "ISO 9283 test cube centre (robot base frame, m); required on a station"),
        # ISO 9283's cube is as large as the used working space allows; under 5 cm it tests nothing a
        # tracker's noise would not hide, over 2 m no UR reaches its corners
        "edge": Key("float?", None, _quantity("cube edge"),
                    "test cube edge (m); default a quarter of the arm's reach"),
        # ISO 9283 §7.2: 30 cycles; repeatability's S_l needs 2, 100 is more than any acceptance asks
        "cycles": Key("int", 30, _quantity("cycles"), "cycles of the pose test (ISO 9283: 30)"),
    },
    "store": {
        "url": Key("str", "", store_url_problem, help="the store: an SQLite file path or a postgresql:// URL "
                                                "shared by a plant's stations (default: store.path)"),
        "path": Key("str", "", help="SQLite database (default: the user's data directory)"),
    },
}


@dataclass(frozen=True)
class StationConfig:
    """A validated station configuration: ``config.section["key"]`` or ``config.get("robot.speed")``."""

    values: dict[str, dict[str, Any]]
    source: str = "<defaults>"
    raw: dict[str, Any] = field(default_factory=dict, repr=False)

    def get(self, dotted: str) -> Any:
        section, key = dotted.split(".", 1)
        return self.values[section][key]

    def __getattr__(self, section: str) -> dict[str, Any]:
        try:
            return self.values[section]
        except KeyError:
            raise AttributeError(section) from None

    def with_overrides(self, **dotted: Any) -> StationConfig:
        """A copy with some keys replaced (``robot__address="127.0.0.5"``), re-validated."""
        merged = {s: dict(v) for s, v in self.values.items()}
        for name, value in dotted.items():
            section, key = name.split("__", 1)
            merged[section][key] = value
        return parse_config(merged, self.source)

    def as_dict(self) -> dict[str, dict[str, Any]]:
        return {s: {k: _plain(v) for k, v in d.items()} for s, d in self.values.items()}

    @property
    def payload(self) -> Any:
        """The robot's `hil.arm.payload.Payload` (None: nothing on the flange)."""
        return self.values["robot"]["payload"]

    @property
    def gravity(self) -> Any:
        """Gravity (m/s²) in the robot base frame, from ``robot.mounting``."""
        from hil.arm.payload import gravity_of_mounting

        return gravity_of_mounting(self.values["robot"]["mounting"])


def _plain(v: Any) -> Any:
    """A config value as TOML/JSON holds it (tuples as lists, a payload as its table)."""
    if isinstance(v, tuple):
        return list(v)
    if hasattr(v, "to_dict"):
        return v.to_dict()
    return v


def _coerce(value: Any, key: Key, where: str) -> Any:
    kind = key.kind.rstrip("?")
    if value is None and key.kind.endswith("?"):
        return None
    if kind == "str":
        if not isinstance(value, str):
            raise InputError(f"{where}: must be a string, got {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise InputError(f"{where}: must be true or false, got {value!r}")
        return value
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"{where}: must be an integer, got {value!r}")
        return value
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, int | float):  # the range: key.check
            raise InputError(f"{where}: must be a number, got {value!r}")
        return float(value)
    if kind == "payload":
        from hil.arm.payload import Payload

        # with_overrides re-parses the parsed values: a Payload is already checked
        if isinstance(value, Payload):
            return value
        if isinstance(value, dict) and "com" not in value and value.get("mass") not in (0, 0.0, None):
            # as --payload MASS,X,Y,Z: a mass without its centre of mass would be put at the flange,
            # a moment arm of zero, and the compliance the payload reveals would be fitted wrongly
            raise InputError(f"{where}: a payload's mass needs its centre of mass: "
                             "com = [x, y, z] (m, flange frame)")
        return Payload.from_dict(value, where)
    if kind == "vec3":
        ok = (isinstance(value, list | tuple) and len(value) == 3
              and all(isinstance(v, int | float) and not isinstance(v, bool) for v in value))
        if not ok:
            raise InputError(f"{where}: must be a list of three numbers [x, y, z], got {value!r}")
        return tuple(float(v) for v in value)
    raise AssertionError(kind)


def parse_config(data: dict[str, Any], source: str = "<config>") -> StationConfig:
    """Validate a parsed TOML document against `SCHEMA`; InputError naming the key on any problem."""
    values: dict[str, dict[str, Any]] = {}
    for section in data:
        if section not in SCHEMA:
            raise InputError(f"{source}: unknown section [{section}] "
                             f"(known: {', '.join(SCHEMA)})")
        if not isinstance(data[section], dict):
            raise InputError(f"{source}: {section}: must be a table [{section}]")
    for section, keys in SCHEMA.items():
        given = data.get(section, {})
        for name in given:
            if name not in keys:
                raise InputError(f"{source}: unknown key {section}.{name} "
                                 f"(known in [{section}]: {', '.join(keys)})")
        out = {}
        for name, key in keys.items():
            where = f"{source}: {section}.{name}"
            value = _coerce(given[name], key, where) if name in given else key.default
            if value is not None and key.check is not None and name in given:
                problem = key.check(value)
                if problem:
                    raise InputError(f"{where}: {problem}")
            out[name] = value
        values[section] = out
    problem = tracker_url_problem(values["tracker"]["url"], values["tracker"]["protocol"])
    if problem:
        raise InputError(f"{source}: tracker.url: {problem}")
    lo, hi = values["keep_in"]["min"], values["keep_in"]["max"]
    if any(a >= b for a, b in zip(lo, hi, strict=True)):
        raise InputError(f"{source}: keep_in.min must be below keep_in.max on every axis")
    warmup = values["warmup"]
    if warmup["max_time"] < warmup["interval"]:
        raise InputError(f"{source}: warmup.max_time: {warmup['max_time']:g} s is shorter than one "
                         f"warmup.interval ({warmup['interval']:g} s): the warm-up could not check the arm "
                         "once")
    if values["campaign"]["mode"] == "sweep":
        problem = sweep_refused(values["tracker"]["protocol"])
        if problem:
            raise InputError(f"{source}: campaign.mode: {problem}")
        if values["campaign"]["stop_early"]:  # it would be silently ignored
            raise InputError(f"{source}: campaign.stop_early: a sweep passes every calibration pose in one "
                             "tour; stopping early is stop-and-go's (campaign.mode = \"stop-and-go\")")
    val, clusters = values["campaign"]["validation_poses"], values["campaign"]["validation_clusters"]
    if clusters > val:
        raise InputError(f"{source}: campaign.validation_clusters: {clusters} clusters for "
                         f"campaign.validation_poses = {val} poses: at most one cluster per pose")
    if clusters and val % clusters:
        raise InputError(f"{source}: campaign.validation_clusters: {clusters} does not divide "
                         f"campaign.validation_poses ({val}) into clusters of equal size")
    cal, robot = values["campaign"]["calibration_poses"], values["robot"]["type"]
    compliance = values["campaign"]["compliance"]
    if 3 * cal < _ALL_PARAMETERS + 6 * compliance + 3:  # else enough for any arm, known without kinematics
        from hil.arm.payload import gravity_of_mounting

        need, n = minimum_calibration_poses(robot, compliance, values["robot"]["payload"],
                                            gravity_of_mounting(values["robot"]["mounting"]))
        if cal < need:
            raise InputError(f"{source}: campaign.calibration_poses: {cal} is too few: identifying the {n} "
                             f"parameters of a {robot} from 3 coordinates per pose needs at least {need}")
    return StationConfig(values, source, data)


def load_config(path: str | os.PathLike[str]) -> StationConfig:
    """Read and validate a station TOML file."""
    name = str(path)
    try:
        data = tomllib.loads(read_input_text(path, "a TOML file", limit=MAX_CONFIG_BYTES))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: not valid TOML: {exc}") from None
    except RecursionError:  # arrays nested thousands deep: tomllib recurses once per level
        raise InputError(f"{name}: not a usable TOML file (nested too deeply)") from None
    return parse_config(data, name)


def check_runnable(config: StationConfig) -> StationConfig:
    """`config` if a campaign can run on it: the keys every file may leave out but a station cannot
    (the tracker's URL). Called on ``--config`` before the store is opened, so an empty file is refused
    without leaving a new database behind (`load_config` alone also serves ``hil history --config``,
    which needs only ``store.path``)."""
    if not config.tracker["url"]:
        raise InputError(f"{config.source}: tracker.url: the tracker's serial device or URL is required "
                         "(e.g. /dev/ttyUSB0, socket://host:port, tcp://host:700)")
    return config


def default_config() -> StationConfig:
    """Every key at its default (what ``--sim`` starts from)."""
    return parse_config({}, "<defaults>")
