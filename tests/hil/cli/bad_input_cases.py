"""The adversarial sweep's table: bad inputs for every `hil` subcommand, and how one is judged.

Shared by tests/hil/cli/test_bad_input_sweep.py (one test per case) and bench/adversarial.py (the
figures for an issue's closing note), so both measure exactly the same thing.

Each `Case` is a command line (run in-process through `hil.cli.main`) plus the files it needs in a fresh
directory of its own. The contract checked for a case that expects exit code 2
(docs/design.md, Contracts: exit codes and errors):

* exit code 2, exactly one line on stderr, no "Traceback";
* that line names what is wrong: every entry of `Case.names` appears in it (``"a|b"``: either);
* no file in the case's directory changed, vanished or appeared (inputs, stores, outputs, a database
  a failed command must not create — the default database location is inside the directory too);
* nothing was started: the simulated station, the hardware drivers, the TUI app and ``hil sim``'s
  server are replaced by tripwires for the duration of a case, because bad input must be refused up
  front, before anything is written or moved. Cases marked ``station=True`` (a robot type checked
  against the controller) do connect, to a real simulated station, but any motion is a tripwire.

Cases that expect exit code 0 (reading a store on read-only media) are checked for the exit code, no
traceback and no change on disk.

Nothing here is skipped or marked expected-to-fail: a case stays red until the product meets it.
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import math
import os
import re
import resource
import shutil
import signal
import sqlite3
import subprocess
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "hil" / "moveb" / "examples"

#: A file's content in a case: text, bytes, or made from the case directory (the valid fixtures are there).
Content = str | bytes | Callable[[Path], str | bytes]


@dataclass(frozen=True)
class Case:
    """One bad input: `argv` after ``hil`` (``{name}`` is replaced by the path of ``name`` in the case's
    directory, ``{dir}`` by the directory), `files` written there first, what the error must name."""

    cmd: str
    id: str
    argv: tuple[str, ...]
    names: tuple[str, ...]
    files: Mapping[str, Content] = field(default_factory=dict, repr=False)
    expect: int = 2
    env: Mapping[str, str] = field(default_factory=dict)
    read_only: tuple[str, ...] = ()
    station: bool = False  # connects to a real simulated station (motion is still a tripwire)
    timeout: float = 15.0  # s: a hang fails the case (the first case of a command also pays its imports)
    fifos: tuple[str, ...] = ()  # named pipes made in the directory (no writer: reading one would hang)
    stdout: str = ""  # "full": every write fails with ENOSPC (> /dev/full); "closed": none (>&-)
    ascii: bool = False  # stdout and stderr encode ASCII only (PYTHONIOENCODING=ascii, the C locale)

    @property
    def name(self) -> str:
        return f"{self.cmd}:{self.id}"


@dataclass
class Outcome:
    """What a case did and which parts of the contract it broke (empty `problems`: it met it)."""

    case: Case
    code: int | None
    err: str
    problems: list[str]
    seconds: float

    @property
    def ok(self) -> bool:
        return not self.problems


# --------------------------------------------------------------------------------------------------
# Valid fixtures, built once (tests: per module; bench: per run)

FIXTURE_FILES = ("truth.json", "measurements.csv", "validation.csv", "model.json", "joints.csv",
                 "station.toml", "store.db", "result.json", "square.moveb")

BASE_CONFIG: dict[str, dict[str, Any]] = {
    "station": {"name": "cell-1"},
    "robot": {"type": "ur5e", "address": "192.168.1.10", "speed": 0.5, "acceleration": 1.0,
              "settle_time": 0.3, "joint_samples": 10},
    "tracker": {"protocol": "geocom", "url": "/dev/ttyUSB0", "baudrate": 115200, "parity": "N",
                "timeout": 3.0, "temperature": 20.0, "pressure": 1013.25, "humidity": 50.0,
                "reflector": "", "measure_time": 0.5, "warmup": 0.0, "bird_bath": False},
    "smr": {"offset": [0.0, 0.0, 0.045], "acceptance_angle": 30.0},
    "keep_in": {"min": [-1.0, -1.0, 0.05], "max": [1.0, 1.0, 1.2]},
    "campaign": {"calibration_poses": 30, "validation_poses": 20, "bootstrap_poses": 6, "samples": 5,
                 "stability": 50e-6, "acceptance": 0.1e-3, "index": "O1", "candidates": 20000, "seed": 1},
    "timeouts": {"connect": 10.0, "move": 60.0, "measure": 10.0, "suspend": 600.0, "relock": 30.0},
    "store": {"path": ""},
}


class Raw(str):
    """A TOML value written as is (wrong types, `nan`)."""


def _toml_value(v: Any) -> str:
    if isinstance(v, Raw):
        return str(v)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf
                                            else repr(v))
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return str(v)


def toml_text(config: Mapping[str, Mapping[str, Any]]) -> str:
    """A station TOML from section -> key -> value."""
    out = []
    for section, keys in config.items():
        if not isinstance(keys, Mapping):
            out.append(f"{section} = {_toml_value(keys)}\n")
            continue
        out.append(f"[{section}]\n")
        out.extend(f"{k} = {_toml_value(v)}\n" for k, v in keys.items())
        out.append("\n")
    return "".join(out)


def config_with(dotted: str, value: Any, base: Mapping[str, Mapping[str, Any]] = BASE_CONFIG) -> str:
    """The base config with one key replaced."""
    section, key = dotted.split(".")
    doc = {s: dict(v) for s, v in base.items()}
    doc[section][key] = value
    return toml_text(doc)


def build_fixtures(out: Path) -> Path:
    """Valid inputs for every subcommand, made with hil itself (synth, identify, the store API)."""
    import numpy as np

    from hil.calibration.identification import identify, validate
    from hil.calibration.measurements import Measurements, read_measurements
    from hil.campaign.events import ModelIdentified, PointMeasured, RunFinished, RunStarted, ValidationDone
    from hil.cli import main
    from hil.report import mes_result, report_data_from
    from hil.station.config import default_config
    from hil.store import RobotIdentity, Store

    out.mkdir(parents=True, exist_ok=True)
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["synth", "--ideal", "--robot", "ur5e", "--poses", "30", "--validation", "12",
                     "--seed", "3", "--out-dir", str(out)]) == 0
        assert main(["identify", "--robot", "ur5e", "--measurements", str(out / "measurements.csv"),
                     "--out", str(out / "model.json")]) == 0
    cal = read_measurements(out / "measurements.csv")
    val = read_measurements(out / "validation.csv")
    rows = "\n".join(",".join(repr(float(v)) for v in q) for q in val.q)
    (out / "joints.csv").write_text("q1,q2,q3,q4,q5,q6\n" + rows + "\n")
    (out / "station.toml").write_text(toml_text(BASE_CONFIG))
    shutil.copy(EXAMPLES / "square.moveb", out / "square.moveb")

    fit = identify(Measurements.from_arrays(cal.q, cal.p, "cal.csv"), "ur5e")
    vm = Measurements.from_arrays(val.q, val.p, "val.csv")
    data = report_data_from(fit, validate(fit.baseline, vm), validate(fit.geometry, vm), default_config(),
                            campaign="C-0001", robot=RobotIdentity("ur5e", "20235500001", software="5.15"),
                            started=1.7e9, finished=1.7e9 + 600, accept_rms=1e-4, calibration=cal,
                            validation=vm)
    (out / "result.json").write_text(json.dumps(mes_result(data), indent=2) + "\n")

    model = json.loads((out / "model.json").read_text())
    with Store.open(out / "store.db") as s:
        cid = s.create_campaign(default_config().as_dict(),
                                RobotIdentity("ur5e", "20235500001", "UR5e", "5.15"),
                                {"method": "tabu"}, now=1.7e9)
        s.save_plan(cid, [(i, "calibration" if i < 30 else "validation", [float(v) for v in q])
                          for i, q in enumerate(np.vstack([cal.q, val.q]))])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="station", poses=42))
        for i, (q, p) in enumerate(zip(np.vstack([cal.q, val.q]), np.vstack([cal.p, val.p]), strict=True)):
            role = "calibration" if i < 30 else "validation"
            s.record_event(PointMeasured(campaign=cid, index=i, role=role, q=[float(v) for v in q],
                                         p=[float(v) for v in p], p_spread=[0.0] * 3, samples=5))
        s.record_event(ModelIdentified(campaign=cid, rms=18e-6, max=45e-6, iterations=6, rejected=[],
                                       model=model))
        s.record_event(ValidationDone(campaign=cid, before={"count": 12, "rms": 1.8e-3, "max": 2e-3},
                                      after={"count": 12, "rms": 21e-6, "max": 40e-6}, passed=True))
        s.record_event(RunFinished(campaign=cid, status="accepted"))
    for name in FIXTURE_FILES:
        assert (out / name).is_file(), name
    return out


# --------------------------------------------------------------------------------------------------
# Bad file contents (functions of the case directory, where the valid fixtures are)

def _lines(d: Path, name: str) -> list[str]:
    return (d / name).read_text().splitlines()


def csv_with(name: str, line: int, column: int, value: str) -> Callable[[Path], str]:
    """`name` (a fixture CSV) with one field replaced (line 1 is the header)."""
    def make(d: Path) -> str:
        lines = _lines(d, name)
        fields = lines[line - 1].split(",")
        fields[column] = value
        lines[line - 1] = ",".join(fields)
        return "\n".join(lines) + "\n"
    return make


def csv_columns(name: str, columns: Sequence[int], value: str) -> Callable[[Path], str]:
    """`name` with the given columns set to one value on every data line."""
    def make(d: Path) -> str:
        lines = _lines(d, name)
        for i in range(1, len(lines)):
            fields = lines[i].split(",")
            for c in columns:
                fields[c] = value
            lines[i] = ",".join(fields)
        return "\n".join(lines) + "\n"
    return make


def csv_header_as(name: str, header: str, extra: str = "") -> Callable[[Path], str]:
    """`name` with its header replaced by `header` and `extra` appended to every data line: the same
    numbers declared in another form (a measurements form of docs/design.md, or a broken one)."""
    def make(d: Path) -> str:
        lines = _lines(d, name)
        return "\n".join([header, *(line + extra for line in lines[1:])]) + "\n"
    return make


def csv_head(name: str, rows: int) -> Callable[[Path], str]:
    return lambda d: "\n".join(_lines(d, name)[:rows + 1]) + "\n"


def csv_drop_column(name: str, column: int) -> Callable[[Path], str]:
    def make(d: Path) -> str:
        return "\n".join(",".join(f for i, f in enumerate(line.split(",")) if i != column)
                         for line in _lines(d, name)) + "\n"
    return make


def json_with(name: str, path: Sequence[str | int], value: Any, *, raw: str | None = None
              ) -> Callable[[Path], str]:
    """Fixture JSON `name` with the value at `path` replaced (or deleted when `value` is DELETE);
    `raw` puts literal JSON text there (NaN, 1e400)."""
    def make(d: Path) -> str:
        doc = json.loads((d / name).read_text())
        node = doc
        for key in path[:-1]:
            node = node[key]
        if value is DELETE:
            del node[path[-1]]
        else:
            node[path[-1]] = "@@RAW@@" if raw is not None else value
        text = json.dumps(doc, indent=1)
        return text.replace('"@@RAW@@"', raw) if raw is not None else text
    return make


DELETE = object()
DEEP_JSON = "[" * 100_000 + "]" * 100_000
BINARY = bytes(range(256)) * 64
HUGE_FIELD = "1" * (200 * 1024)  # a CSV field over 128 KiB


def utf16(name: str) -> Callable[[Path], bytes]:
    return lambda d: b"\xff\xfe" + (d / name).read_text().encode("utf-16-le")


def moveb_line(line: str, at: int = 2) -> Callable[[Path], str]:
    """square.moveb with program line `at` (1-based, counting MOVEB lines) replaced."""
    def make(d: Path) -> str:
        lines = _lines(d, "square.moveb")
        idx = [i for i, s in enumerate(lines) if s.strip().upper().startswith("MOVEB")][at - 1]
        lines[idx] = line
        return "\n".join(lines) + "\n"
    return make


def corrupt_store(d: Path) -> bytes:
    """store.db with its middle third overwritten: "a database corrupted mid-file"."""
    raw = bytearray((d / "store.db").read_bytes())
    third = len(raw) // 3
    raw[third:2 * third] = b"\xa5" * third
    return bytes(raw)


def truncated_store(d: Path) -> bytes:
    """store.db cut off in the middle (a copy that did not finish)."""
    raw = (d / "store.db").read_bytes()
    return raw[:len(raw) // 2]


def newer_store(d: Path) -> bytes:
    """store.db claiming a schema version this hil does not know."""
    tmp = d / ".newer.tmp"
    shutil.copy(d / "store.db", tmp)
    conn = sqlite3.connect(tmp)
    conn.execute("PRAGMA user_version = 999")
    conn.commit()
    conn.close()
    data = tmp.read_bytes()
    tmp.unlink()
    return data


def foreign_sqlite(d: Path) -> bytes:
    """An SQLite database that is not a hil store."""
    tmp = d / ".foreign.tmp"
    conn = sqlite3.connect(tmp)
    conn.execute("CREATE TABLE photos (id INTEGER PRIMARY KEY, name TEXT)")
    conn.commit()
    conn.close()
    data = tmp.read_bytes()
    tmp.unlink()
    return data


def damaged_store(sql: str) -> Callable[[Path], bytes]:
    """store.db with one row damaged by `sql` (a JSON column overwritten with text that does not
    parse): what a disk error or a tool writing into the database leaves."""
    def make(d: Path) -> bytes:
        tmp = d / ".damaged.tmp"
        shutil.copy(d / "store.db", tmp)
        conn = sqlite3.connect(tmp)
        conn.execute(sql)
        conn.commit()
        conn.close()
        data = tmp.read_bytes()
        for p in d.glob(".damaged.tmp*"):
            p.unlink()
        return data
    return make


def empty_store(d: Path) -> bytes:
    """A valid hil store without a campaign."""
    from hil.store import Store

    tmp = d / ".empty-store.tmp"
    with Store.open(tmp):
        pass
    data = tmp.read_bytes()
    for p in d.glob(".empty-store.tmp*"):
        p.unlink()
    return data


# --------------------------------------------------------------------------------------------------
# The table

BAD_FLOATS = ("-1", "0", "nan", "inf", "-inf", "1e308", "abc")
BAD_COUNTS = ("-1", "0", "abc", "1.5")


def _cases() -> list[Case]:
    cases: list[Case] = []

    def add(cmd: str, id: str, argv: Sequence[str], names: Sequence[str] = (), **kw: Any) -> None:
        cases.append(Case(cmd, id, tuple(argv), tuple(names), **kw))

    def numbers(cmd: str, base: Sequence[str], option: str, values: Sequence[str], **kw: Any) -> None:
        for v in values:
            add(cmd, f"{option}={v}", [*base, f"{option}={v}"], [option], **kw)

    # --- files every reader must refuse, by kind
    def bad_files(cmd: str, argv_of: Callable[[str], list[str]], option: str, kind: str) -> None:
        """missing, directory, empty, binary, UTF-16 and garbage files given to `option`."""
        add(cmd, f"{option}:missing", argv_of("{dir}/nothing-here"), ["nothing-here"])
        add(cmd, f"{option}:directory", argv_of("{dir}/sub"), ["/sub"])
        add(cmd, f"{option}:empty", argv_of("{dir}/empty.x"), ["empty.x"], files={"empty.x": ""})
        add(cmd, f"{option}:binary", argv_of("{dir}/binary.x"), ["binary.x"], files={"binary.x": BINARY})
        add(cmd, f"{option}:garbage", argv_of("{dir}/garbage.x"), ["garbage.x"],
            files={"garbage.x": f"hello, this is not {{a {kind}\n"})

    def bad_json(cmd: str, argv_of: Callable[[str], list[str]], option: str, name: str) -> None:
        """`name` (model/truth/result JSON) broken in the ways JSON can be, and with wrong types."""
        bad_files(cmd, argv_of, option, "JSON")
        add(cmd, f"{option}:deep-nesting", argv_of("{dir}/deep.json"), ["deep.json"],
            files={"deep.json": lambda d: DEEP_JSON})
        add(cmd, f"{option}:utf16", argv_of("{dir}/u16.json"), ["u16.json"], files={"u16.json": utf16(name)})
        add(cmd, f"{option}:top-level-list", argv_of("{dir}/list.json"), ["list.json"],
            files={"list.json": "[1, 2, 3]\n"})
        add(cmd, f"{option}:wrong-format", argv_of("{dir}/fmt.json"), ["fmt.json"],
            files={"fmt.json": json_with(name, ["format"], "hil-model/99")})
        if name in ("model.json", "truth.json"):
            geometry = [
                ("robot-unknown", ["robot"], "ur99", None),
                ("robot-number", ["robot"], 5, None),
                ("joints-5", ["joints"], [{"xyz": [0, 0, 0.1], "rpy": [0, 0, 0]}] * 5, None),
                ("xyz-true", ["joints", 1, "xyz"], [True, 0, 0], None),
                ("xyz-string-1", ["joints", 1, "xyz"], ["1", 0, 0], None),
                ("xyz-1e308", ["joints", 2, "xyz"], [1e308, 0, 0], None),
                ("xyz-1e400", ["joints", 2, "xyz"], None, "[1e400, 0, 0]"),
                ("xyz-NaN", ["joints", 2, "xyz"], None, "[NaN, 0, 0]"),
                ("rpy-null", ["joints", 0, "rpy"], None, "null"),
                ("smr-2", ["smr"], [0.0, 0.0], None),
                ("smr-true", ["smr"], [True, True, True], None),
                ("smr-10m", ["smr"], [10.0, 0.0, 0.0], None),
                ("tracker-missing", ["tracker"], DELETE, None),
                ("tracker-1e308", ["tracker", "xyz"], [1e308, 0, 0], None),
                ("flange-string", ["flange"], "flange", None),
            ]
            for ident, path, value, raw in geometry:
                fname = f"{ident}.json"
                add(cmd, f"{option}:{ident}", argv_of("{dir}/" + fname), [fname],
                    files={fname: json_with(name, path, value, raw=raw)})
        if name == "truth.json":
            for ident, path, value in (("noise-missing", ["noise"], DELETE),
                                       ("noise-negative", ["noise", "tracker_sigma"], -1.0),
                                       ("noise-string", ["noise", "tracker_sigma"], "1"),
                                       ("noise-1e308", ["noise", "tracker_sigma"], 1e308)):
                fname = f"{ident}.json"
                add(cmd, f"{option}:{ident}", argv_of("{dir}/" + fname), [fname],
                    files={fname: json_with(name, path, value)})

    def bad_csv(cmd: str, argv_of: Callable[[str], list[str]], option: str, name: str,
                xyz: bool = True) -> None:
        """`name` (a measurements or joints CSV) broken in the ways a table can be."""
        bad_files(cmd, argv_of, option, "CSV")
        last = 8 if xyz else 5
        variants: list[tuple[str, Content]] = [
            ("header-only", lambda d: _lines(d, name)[0] + "\n"),
            ("utf16", utf16(name)),
            ("text-number", csv_with(name, 3, 2, "abc")),
            ("nan", csv_with(name, 3, last, "nan")),
            ("inf", csv_with(name, 4, last, "inf")),
            ("1e308", csv_with(name, 4, last, "1e308")),
            ("empty-field", csv_with(name, 5, 0, "")),
            ("huge-field", csv_with(name, 3, 1, HUGE_FIELD)),
            ("ragged-row", lambda d: "\n".join([*_lines(d, name)[:3], "1,2,3", *_lines(d, name)[3:]]) + "\n"),
            ("missing-column", csv_drop_column(name, last)),
            ("joint-100rad", csv_with(name, 3, 0, "100")),
        ]
        if xyz:
            variants.append(("position-1km", csv_with(name, 3, 6, "1000")))
        for ident, content in variants:
            fname = f"{ident}.csv"
            add(cmd, f"{option}:{ident}", argv_of("{dir}/" + fname), [fname], files={fname: content})

    def bad_forms(cmd: str, argv_of: Callable[[str], list[str]], name: str, xyz: bool = True) -> None:
        """`name` in a header form that is incomplete, ambiguous or contradicts ``--joint-units``
        (docs/design.md, Contracts: Measurements CSV), and ``--joint-units`` itself wrong."""
        joints_deg = ",".join(f"q{i}_deg" for i in range(1, 7))
        tail = ",x,y,z" if xyz else ""
        variants: list[tuple[str, Content, list[str], list[str]]] = [
            ("joint-degrees-as-radians", csv_with(name, 3, 0, "90"), [], ["q1_deg", "--joint-units deg"]),
            ("mixed-joint-units", csv_header_as(name, "q1_deg,q2,q3,q4,q5,q6" + tail), [], ["mix units"]),
            ("degrees-but-joint-units-rad", csv_header_as(name, joints_deg + tail), ["--joint-units", "rad"],
             ["--joint-units", "deg"]),
            ("two-joint-forms", csv_header_as(name, "q1,q2,q3,q4,q5,q6" + tail + ",shoulder_pan_joint,"
                                              "shoulder_lift_joint,elbow_joint,wrist_1_joint,wrist_2_joint,"
                                              "wrist_3_joint", ",0,0,0,0,0,0"), [], ["keep one joint form"]),
            ("no-joint-form", csv_header_as(name, "a1,a2,a3,a4,a5,a6" + tail), [], ["no joint columns"]),
        ]
        if xyz:
            q = "q1,q2,q3,q4,q5,q6"
            variants += [
                ("no-position-form", csv_header_as(name, f"{q},a,b,c"), [], ["no position columns"]),
                ("polar-without-distance", csv_header_as(name, f"{q},hz,v,c"), [], ["missing column(s) d"]),
                ("cartesian-and-polar", csv_header_as(name, f"{q},x,y,z,hz,v,d", ",0.1,1.5,2"), [],
                 ["x,y,z", "hz,v,d"]),
                ("polar-zero-distance", csv_header_as(name, f"{q},a,b,c,hz,v,d", ",0.1,1.5,0"), [],
                 ["column d", "distance"]),
                ("polar-degrees-as-radians", csv_header_as(name, f"{q},a,b,c,hz,v,d", ",120,80,2"), [],
                 ["column hz", "_deg"]),
                ("marker-without-z2", csv_header_as(name, f"{q},x1,y1,z1,x2,y2", ",0.1,0.2"), [],
                 ["marker 2", "z2"]),
                ("marker-gap", csv_header_as(name, f"{q},x1,y1,z1,x3,y3,z3", ",0.1,0.2,0.3"), [],
                 ["marker 3"]),
                ("quaternion-not-unit", csv_header_as(name, f"{q},x,y,z,qw,qx,qy,qz", ",1,1,0,0"), [],
                 ["qw,qx,qy,qz", "unit quaternion"]),
                ("rpy-without-yaw", csv_header_as(name, f"{q},x,y,z,roll,pitch", ",0,0"), [],
                 ["missing column(s) yaw"]),
                ("rpy-degrees-as-radians", csv_header_as(name, f"{q},x,y,z,roll,pitch,yaw", ",90,0,0"), [],
                 ["column roll", "_deg"]),
            ]
        for ident, content, options, names in variants:
            fname = f"{ident}.csv"
            add(cmd, f"{option_of(cmd)}:{ident}", [*argv_of("{dir}/" + fname), *options], [fname, *names],
                files={fname: content})
        for v in ("grad", "", "DEG"):
            add(cmd, f"--joint-units={v}", [*argv_of(f"{{dir}}/{name}"), f"--joint-units={v}"],
                ["--joint-units"])

    def option_of(cmd: str) -> str:
        return "--joints" if cmd == "fk" else "--measurements"

    def bad_program(cmd: str, argv_of: Callable[[str], list[str]]) -> None:
        bad_files(cmd, argv_of, "PROGRAM", "MOVEB")
        variants: list[tuple[str, Content]] = [
            ("coordinate-4e12", moveb_line("MOVEB 4e12 -50 300  0 0 -1  1 0 0  0.5 0.2")),
            ("coordinate-nan", moveb_line("MOVEB nan -50 300  0 0 -1  1 0 0  0.5 0.2")),
            ("coordinate-inf", moveb_line("MOVEB 500 inf 300  0 0 -1  1 0 0  0.5 0.2")),
            ("coordinate-1e308", moveb_line("MOVEB 500 -50 1e308  0 0 -1  1 0 0  0.5 0.2")),
            ("too-few-fields", moveb_line("MOVEB 500 -50 300")),
            ("unknown-keyword", moveb_line("MOVEX 500 -50 300  0 0 -1  1 0 0  0.5 0.2")),
            ("D-negative", moveb_line("MOVEB 500 -50 300  0 0 -1  1 0 0  -0.5 0.2")),
            ("E-negative", moveb_line("MOVEB 500 -50 300  0 0 -1  1 0 0  0.5 -0.2")),
            ("D-1e308", moveb_line("MOVEB 500 -50 300  0 0 -1  1 0 0  1e308 0.2")),
            ("zero-axis", moveb_line("MOVEB 500 -50 300  0 0 0  1 0 0  0.5 0.2")),
            ("parallel-axes", moveb_line("MOVEB 500 -50 300  1 0 0  1 0 0  0.5 0.2")),
            ("one-point", lambda d: "MOVEB 400 -50 300  0 0 -1  1 0 0  0.5 0.2\n"),
            ("huge-line", moveb_line("MOVEB " + HUGE_FIELD + " -50 300  0 0 -1  1 0 0  0.5 0.2")),
            ("utf16", utf16("square.moveb")),
        ]
        for ident, content in variants:
            fname = f"{ident}.moveb"
            add(cmd, f"PROGRAM:{ident}", argv_of("{dir}/" + fname), [fname], files={fname: content})

    def bad_configs(cmd: str, argv_of: Callable[[str], list[str]], keys: Sequence[tuple[str, Any]] | None
                    = None, files_too: bool = True) -> None:
        """Station configs: every key with a wrong type or an absurd value, and broken TOML files."""
        for dotted, value in keys if keys is not None else CONFIG_VALUES:
            label = value if isinstance(value, Raw) else _toml_value(value)
            fname = "bad.toml"
            add(cmd, f"config:{dotted}={label}"[:90], argv_of("{dir}/" + fname), [dotted],
                files={fname: config_with(dotted, value)})
        if not files_too:
            return
        bad_files(cmd, argv_of, "--config", "TOML")
        add(cmd, "config:empty-file-no-tracker-url", argv_of("{dir}/empty.toml"), ["tracker.url"],
            files={"empty.toml": ""})
        add(cmd, "config:deep-nesting", argv_of("{dir}/deep.toml"), ["deep.toml"],
            files={"deep.toml": lambda d: "a = " + "[" * 100_000 + "]" * 100_000 + "\n"})
        add(cmd, "config:unknown-key", argv_of("{dir}/typo.toml"), ["robot.sped"],
            files={"typo.toml": toml_text({"robot": {"sped": 0.5}})})
        add(cmd, "config:unknown-section", argv_of("{dir}/typo.toml"), ["robt"],
            files={"typo.toml": toml_text({"robt": {"speed": 0.5}})})
        add(cmd, "config:section-not-table", argv_of("{dir}/typo.toml"), ["robot"],
            files={"typo.toml": "robot = 5\n"})
        add(cmd, "config:huge-file", argv_of("{dir}/huge.toml"), ["huge.toml"],
            files={"huge.toml": lambda d: "# " + "x" * (20 * 1024 * 1024) + "\n"})

    d = "{dir}"
    # ---------------------------------------------------------------- calibrate
    cal = ["calibrate", "--sim", "--db", f"{d}/cal.db", "--out", f"{d}/result-out.json"]
    numbers("calibrate", cal, "--speed", BAD_FLOATS)
    numbers("calibrate", cal, "--seed", ("-1", "abc", "1.5"))
    numbers("calibrate", cal, "--poses", (*BAD_COUNTS, "3", "100000000"))
    numbers("calibrate", cal, "--validation", (*BAD_COUNTS, "100000000"))
    numbers("calibrate", cal, "--candidates", (*BAD_COUNTS, "1000000000"))
    numbers("calibrate", cal, "--accept", ("-1", "0", "nan", "inf", "0.1", "abc"))
    numbers("calibrate", cal, "--cycles", ("0", "-1", "abc", "1000000"))
    numbers("calibrate", [*cal, "--stop-early"], "--stop-margin", ("0", "-1", "1.5", "nan", "inf", "abc"))
    add("calibrate", "--stop-margin-without-the-rule", [*cal, "--stop-margin", "0.8"], ["--stop-margin"])
    add("calibrate", "--selection=fastest", [*cal, "--selection", "fastest"], ["--selection|fastest"])
    numbers("calibrate", [*cal, "--selection", "time-aware"], "--time-budget",
            ("0", "-1", "nan", "inf", "1e308", "abc"))
    add("calibrate", "--time-budget-without-time-aware", [*cal, "--time-budget", "300"], ["--time-budget"])
    numbers("calibrate", [*cal, "--selection", "time-aware"], "--search-time",
            ("0", "-1", "nan", "inf", "1e308", "abc"))
    add("calibrate", "--search-time-without-time-aware", [*cal, "--search-time", "5"], ["--search-time"])
    numbers("calibrate", [*cal, "--mode", "sweep", "--tracker-protocol", "emscon"], "--sweep-speed",
            ("0", "-1", "nan", "inf", "4", "abc"))
    add("calibrate", "--sweep-speed-without-sweep", [*cal, "--sweep-speed", "1.0"], ["--sweep-speed"])
    add("calibrate", "--plan-cache=a-file", [*cal, "--plan-cache", f"{d}/afile"], ["plan_cache", "afile"],
        files={"afile": "not a directory"})
    add("calibrate", "--robot=ur99", [*cal, "--robot", "ur99"], ["ur99"])
    add("calibrate", "--robot=empty", [*cal, "--robot", ""], ["--robot"])
    add("calibrate", "--tracker-protocol=foo", [*cal, "--tracker-protocol", "foo"], ["--tracker-protocol"])
    bad_json("calibrate", lambda p: [*cal, "--truth", p], "--truth", "truth.json")
    add("calibrate", "--truth=model-not-truth", [*cal, "--truth", f"{d}/model.json"], ["model.json"])
    add("calibrate", "--robot=ur10e-vs-ur5e-truth", [*cal, "--robot", "ur10e", "--truth", f"{d}/truth.json"],
        ["ur10e", "ur5e"])
    add("calibrate", "--out=--db", ["calibrate", "--sim", "--db", f"{d}/store.db", "--out", f"{d}/store.db"],
        ["store.db"])
    add("calibrate", "--out=--truth", [*cal[:-2], "--truth", f"{d}/truth.json", "--out", f"{d}/truth.json"],
        ["truth.json"])
    add("calibrate", "--out=directory", [*cal[:-2], "--out", f"{d}/sub"], ["/sub"])
    add("calibrate", "--report=--db", [*cal, "--report", f"{d}/cal.db"], ["cal.db"])
    add("calibrate", "--report=--truth", [*cal, "--truth", f"{d}/truth.json", "--report", f"{d}/truth.json"],
        ["truth.json"])
    add("calibrate", "--report=--out", [*cal, "--report", f"{d}/result-out.json"], ["result-out.json"])
    add("calibrate", "--report=directory", [*cal, "--report", f"{d}/sub"], ["/sub"])
    add("calibrate", "--out=--config", ["calibrate", "--config", f"{d}/station.toml", "--db", f"{d}/cal.db",
                                        "--out", f"{d}/station.toml"], ["station.toml"])
    add("calibrate", "--db=directory", ["calibrate", "--config", f"{d}/station.toml", "--db", f"{d}/sub"],
        ["/sub"])
    add("calibrate", "--db=truth.json", ["calibrate", "--config", f"{d}/station.toml", "--db",
                                         f"{d}/truth.json"], ["truth.json"])
    # (No "--db=empty-file" case for calibrate: a writer takes a 0-byte file for a new store, as SQLite
    # does, because creating a store leaves one for a moment — between SQLite creating the file and the
    # schema's commit — and a campaign killed in that moment must start again, not be refused. Readers
    # refuse one: see the history/show cases.)
    add("calibrate", "--db=corrupt-mid-file", ["calibrate", "--config", f"{d}/station.toml", "--db",
                                               f"{d}/corrupt.db"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})
    add("calibrate", "--db=newer-schema", ["calibrate", "--config", f"{d}/station.toml", "--db",
                                           f"{d}/newer.db"], ["newer.db"], files={"newer.db": newer_store})
    add("calibrate", "--config-with---speed", ["calibrate", "--config", f"{d}/station.toml", "--speed", "5",
                                               "--db", f"{d}/cal.db"], ["--speed"])
    numbers("calibrate", [*cal, "--verify"], "--verify-cycles", ("0", "1", "abc", "101"))
    add("calibrate", "--verify-cycles-without---verify", [*cal, "--verify-cycles", "3"], ["--verify-cycles"])
    add("calibrate", "--verify:no-verify-centre",
        ["calibrate", "--config", f"{d}/station.toml", "--db", f"{d}/cal.db", "--verify"], ["verify.centre"])
    bad_configs("calibrate", lambda p: ["calibrate", "--config", p, "--db", f"{d}/cal.db"])
    add("calibrate", "config:store.path=number", ["calibrate", "--config", f"{d}/bad.toml"], ["store.path"],
        files={"bad.toml": config_with("store.path", 5)})
    add("calibrate", "config:store.path=directory", ["calibrate", "--config", f"{d}/bad.toml"], ["sub"],
        files={"bad.toml": config_with("store.path", "sub")})
    add("calibrate", "config:store.path=the-config", ["calibrate", "--config", f"{d}/bad.toml"], ["bad.toml"],
        files={"bad.toml": config_with("store.path", "bad.toml")})
    add("calibrate", "config:store.path=truth.json", ["calibrate", "--config", f"{d}/bad.toml"],
        ["truth.json"], files={"bad.toml": config_with("store.path", "truth.json")})
    for robot in ("ur10e", "ur3e"):  # the controller (a simulated UR5e) says otherwise
        add("calibrate", f"config:robot.type={robot}-vs-UR5e-controller",
            ["calibrate", "--config", f"{d}/sim.toml", "--db", f"{d}/cal.db", "--poses", "12",
             "--validation", "4", "--candidates", "500"],
            [robot, "ur5e"], files={"sim.toml": _sim_config(robot)}, station=True, timeout=60)

    # ---------------------------------------------------------------- verify
    ver = ["verify", "--sim", "--db", f"{d}/ver.db", "--out", f"{d}/verify-out.json"]
    numbers("verify", ver, "--speed", BAD_FLOATS)
    numbers("verify", ver, "--seed", ("-1", "abc", "1.5"))
    numbers("verify", ver, "--cycles", ("0", "1", "-1", "abc", "101"))
    add("verify", "--robot=ur99", [*ver, "--robot", "ur99"], ["ur99"])
    add("verify", "--robot=ur10e-vs-ur5e-model", [*ver, "--robot", "ur10e", "--model", f"{d}/model.json"],
        ["ur10e", "ur5e"])
    bad_json("verify", lambda p: [*ver, "--model", p], "--model", "model.json")
    add("verify", "--model=truth", [*ver, "--model", f"{d}/truth.json"], ["truth.json"])
    add("verify", "--out=--model", [*ver[:-2], "--model", f"{d}/model.json", "--out", f"{d}/model.json"],
        ["model.json"])
    add("verify", "--out=directory", [*ver[:-2], "--out", f"{d}/sub"], ["/sub"])
    add("verify", "--report=--out", [*ver, "--report", f"{d}/verify-out.json"], ["verify-out.json"])
    add("verify", "--config-with---speed", ["verify", "--config", f"{d}/station.toml", "--speed", "5",
                                            "--db", f"{d}/ver.db"], ["--speed"])
    add("verify", "config:no-verify-centre",
        ["verify", "--config", f"{d}/station.toml", "--db", f"{d}/ver.db"], ["verify.centre"])
    verify_base = {**BASE_CONFIG, "verify": {"centre": [0.5, 0.0, 0.3], "edge": 0.2, "cycles": 30}}
    for dotted, value, names in (("verify.centre", [1.6, 0.0, 0.3], ["verify.centre", "reach"]),
                                 ("verify.centre", [0.5, 0.0, -0.2], ["verify.centre", "keep-in"]),
                                 ("verify.centre", [500.0, 0.0, 300.0], ["verify.centre"]),
                                 ("verify.edge", 200.0, ["verify.edge"]),
                                 ("verify.edge", 0.0, ["verify.edge"]),
                                 ("verify.cycles", 1, ["verify.cycles"]),
                                 ("verify.cycles", 1000, ["verify.cycles"])):
        add("verify", f"config:{dotted}={_toml_value(value)}", ["verify", "--config", f"{d}/bad.toml", "--db",
                                                                  f"{d}/ver.db"], names,
            files={"bad.toml": config_with(dotted, value, base=verify_base)})
    add("verify", "config:robot.type=ur10e-vs-UR5e-controller",  # the controller (a simulated UR5e) says not
        ["verify", "--config", f"{d}/sim.toml", "--db", f"{d}/ver.db", "--out", f"{d}/verify-out.json"],
        ["ur10e", "ur5e"], files={"sim.toml": _sim_config("ur10e", verify=verify_base["verify"])},
        station=True, timeout=60)

    # ---------------------------------------------------------------- identify
    ident = ["identify", "--robot", "ur5e", "--measurements", f"{d}/measurements.csv"]
    out_model = ["--out", f"{d}/model-out.json"]
    add("identify", "--robot=ur99", ["identify", "--robot", "ur99", "--measurements", f"{d}/measurements.csv",
                                     *out_model], ["ur99"])
    add("identify", "--robot=empty", ["identify", "--robot", "", "--measurements", f"{d}/measurements.csv",
                                      *out_model], ["--robot"])
    bad_csv("identify", lambda p: ["identify", "--robot", "ur5e", "--measurements", p, *out_model],
            "--measurements", "measurements.csv")
    bad_forms("identify", lambda p: ["identify", "--robot", "ur5e", "--measurements", p, *out_model],
              "measurements.csv")
    for ident_, content in (("too-few-rows", csv_head("measurements.csv", 8)),
                            ("constant-xyz", csv_columns("measurements.csv", (6, 7, 8), "1.0")),
                            ("constant-q1", csv_columns("measurements.csv", (0,), "0.1"))):
        add("identify", f"--measurements:{ident_}", ["identify", "--robot", "ur5e", "--measurements",
                                                     f"{d}/{ident_}.csv", *out_model],
            [f"{ident_}.csv"], files={f"{ident_}.csv": content})
    for v in ("1,2", "a,b,c", "nan,0,0", "inf,0,0", "1e308,0,0", "10,0,0"):
        add("identify", f"--smr={v}", [*ident, f"--smr={v}", *out_model], ["--smr"])
    add("identify", "--validation:missing", [*ident, "--validation", f"{d}/nothing.csv", *out_model],
        ["nothing.csv"])
    add("identify", "--validation:garbage", [*ident, "--validation", f"{d}/g.csv", *out_model], ["g.csv"],
        files={"g.csv": "not,a\ncsv"})
    add("identify", "--validation:nan", [*ident, "--validation", f"{d}/n.csv", *out_model], ["n.csv"],
        files={"n.csv": csv_with("validation.csv", 3, 7, "nan")})
    add("identify", "--out=--measurements", [*ident, "--out", f"{d}/measurements.csv"], ["measurements.csv"])
    add("identify", "--out=--measurements-relative", [*ident, "--out", "./measurements.csv"],
        ["measurements.csv"])
    add("identify", "--out=--validation", [*ident, "--validation", f"{d}/validation.csv", "--out",
                                           f"{d}/validation.csv"], ["validation.csv"])
    add("identify", "--out=directory", [*ident, "--out", f"{d}/sub"], ["/sub"])
    add("identify", "--out=store", [*ident, "--out", f"{d}/store.db"], ["store.db"],
        env={"HIL_DB": f"{d}/store.db"})
    for v in ("abc", "3,0,0", "-1", "1e9", "nan", "3,0,0,9"):
        add("identify", f"--payload={v}", [*ident, "--compliance", f"--payload={v}", *out_model],
            ["--payload"])
    for v in ("1,2", "a,b,c", "nan,0,0"):
        add("identify", f"--mounting={v}", [*ident, f"--mounting={v}", *out_model], ["--mounting"])

    # ---------------------------------------------------------------- validate
    val = ["validate", "--model", f"{d}/model.json", "--measurements", f"{d}/validation.csv"]
    numbers("validate", val, "--max-rms", ("-1", "0", "nan", "inf", "0.1", "1e308", "abc"))
    bad_json("validate", lambda p: ["validate", "--model", p, "--measurements", f"{d}/validation.csv"],
             "--model", "model.json")
    bad_csv("validate", lambda p: ["validate", "--model", f"{d}/model.json", "--measurements", p],
            "--measurements", "validation.csv")
    bad_forms("validate", lambda p: ["validate", "--model", f"{d}/model.json", "--measurements", p],
              "validation.csv")

    # ---------------------------------------------------------------- fk
    fk = ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/joints.csv"]
    bad_json("fk", lambda p: ["fk", "--model", p, "--joints", f"{d}/joints.csv", "--out", f"{d}/p.csv"],
             "--model", "model.json")
    bad_csv("fk", lambda p: ["fk", "--model", f"{d}/model.json", "--joints", p, "--out", f"{d}/p.csv"],
            "--joints", "joints.csv", xyz=False)
    bad_forms("fk", lambda p: ["fk", "--model", f"{d}/model.json", "--joints", p, "--out", f"{d}/p.csv"],
              "joints.csv", xyz=False)
    add("fk", "--frame=moon", [*fk, "--frame", "moon", "--out", f"{d}/p.csv"], ["--frame"])
    add("fk", "--point=elbow", [*fk, "--point", "elbow", "--out", f"{d}/p.csv"], ["--point"])
    add("fk", "--out=--joints", [*fk, "--out", f"{d}/joints.csv"], ["joints.csv"])
    add("fk", "--out=--model", [*fk, "--out", f"{d}/model.json"], ["model.json"])
    add("fk", "--out=directory", [*fk, "--out", f"{d}/sub"], ["/sub"])
    for v in ("abc", "2,1", "-3", "inf", "1,0,0,5"):
        add("fk", f"--payload={v}", [*fk, f"--payload={v}", "--out", f"{d}/p.csv"], ["--payload"])

    # ---------------------------------------------------------------- export
    ex = ["export", "--model", f"{d}/model.json", "--format", "urdf"]
    bad_json("export", lambda p: ["export", "--model", p, "--format", "urdf", "--out", f"{d}/m.urdf"],
             "--model", "model.json")
    add("export", "--model=truth", ["export", "--model", f"{d}/truth.json", "--format", "urdf", "--out",
                                    f"{d}/m.urdf"], ["hil-model/1"])
    add("export", "--format=sdf", [*ex[:-2], "--format", "sdf", "--out", f"{d}/m.urdf"], ["--format"])
    add("export", "--out=--model", [*ex[:-2], "--format", "json", "--out", f"{d}/model.json"], ["model.json"])
    add("export", "--out=--model-relative", [*ex, "--out", "./model.json"], ["model.json"])
    add("export", "--out=directory", [*ex, "--out", f"{d}/sub"], ["/sub"])

    # ---------------------------------------------------------------- compensate
    block = {k: [0.0] * 6 for k in ("delta_theta", "delta_a", "delta_d", "delta_alpha")}
    ctl = {"k.json": json.dumps({"robot": "ur5e", "controller": block}),
           "poses.csv": "x,y,z,rx,ry,rz\n-0.4,-0.13,0.45,3.1,0.1,0\n"}
    co = ["compensate", "--model", f"{d}/model.json", "--controller", f"{d}/k.json"]
    bad_json("compensate", lambda p: ["compensate", "--model", p, "--controller", f"{d}/k.json",
                                      f"{d}/joints.csv", "--out", f"{d}/o.csv"], "--model", "model.json")
    add("compensate", "--controller:no-block", [*co[:-1], f"{d}/truth.json", f"{d}/poses.csv", "--out",
                                                f"{d}/o.csv"], ["truth.json", "controller"], files=ctl)
    add("compensate", "--controller:ur10e", [*co, f"{d}/poses.csv", "--out", f"{d}/o.csv"], ["ur10e"],
        files={**ctl, "k.json": json.dumps({"robot": "ur10e", "controller": block})})
    add("compensate", "--controller:delta-in-mm", [*co, f"{d}/poses.csv", "--out", f"{d}/o.csv"],
        ["k.json", "delta_d"], files={**ctl, "k.json": json.dumps({"controller": {**block,
                                                                                   "delta_d": [5.0] * 6}})})
    add("compensate", "--controller:delta-string", [*co, f"{d}/poses.csv", "--out", f"{d}/o.csv"],
        ["k.json", "delta_a"], files={**ctl, "k.json": json.dumps({"controller": {**block,
                                                                                   "delta_a": ["0"] * 6}})})
    add("compensate", "INPUT:unbalanced", [*co, f"{d}/p.script", "--out", f"{d}/o.script"], ["p.script:2"],
        files={**ctl, "p.script": "def f():\n  movel(p[.4, 0, .3, 3.1, 0, 0)\nend\n"})
    add("compensate", "INPUT:pose-of-5", [*co, f"{d}/p.script", "--out", f"{d}/o.script"],
        ["p.script:2", "5"],
        files={**ctl, "p.script": "def f():\n  movel(p[.4, 0, .3, 3.1, 0], a=1.2)\nend\n"})
    add("compensate", "INPUT:unreachable", [*co, f"{d}/p.script", "--out", f"{d}/o.script"], ["p.script:3"],
        files={**ctl, "p.script": "def f():\n  # far away\n  movel(p[4, 0, .3, 0, 3.14, 0])\nend\n"})
    add("compensate", "INPUT:text-in-csv", [*co, f"{d}/t.csv", "--out", f"{d}/o.csv"], ["t.csv", "line 2"],
        files={**ctl, "t.csv": "x,y,z,rx,ry,rz\n0.4,abc,0.3,3.1,0,0\n"})
    add("compensate", "INPUT:millimetres", [*co, f"{d}/t.csv", "--out", f"{d}/o.csv"], ["t.csv", "metres"],
        files={**ctl, "t.csv": "x,y,z,rx,ry,rz\n400,-130,450,3.1,0.1,0\n"})
    add("compensate", "INPUT:missing", [*co, f"{d}/nothing.csv", "--out", f"{d}/o.csv"], ["nothing.csv"],
        files=ctl)
    add("compensate", "INPUT:urp", [*co, f"{d}/p.urp", "--out", f"{d}/o.script"], ["p.urp"],
        files={**ctl, "p.urp": BINARY})
    for v in ("0,0,9,0,0,0", "1,2,3", "nan,0,0,0,0,0"):
        add("compensate", f"--near={v}", [*co, f"{d}/poses.csv", f"--near={v}", "--out", f"{d}/o.csv"],
            ["--near"], files=ctl)
    add("compensate", "--tcp=in-mm", [*co, f"{d}/poses.csv", "--tcp=0,0,150,0,0,0", "--out", f"{d}/o.csv"],
        ["--tcp"], files=ctl)
    add("compensate", "--out=--model", [*co, f"{d}/poses.csv", "--out", f"{d}/model.json"], ["model.json"],
        files=ctl)
    add("compensate", "--out=INPUT", [*co, f"{d}/poses.csv", "--out", f"{d}/poses.csv"], ["poses.csv"],
        files=ctl)
    add("compensate", "--out=directory", [*co, f"{d}/poses.csv", "--out", f"{d}/sub"], ["/sub"], files=ctl)
    add("compensate", "--config:other-robot", ["compensate", "--model", f"{d}/model.json", "--config",
                                                f"{d}/station.toml", f"{d}/poses.csv", "--out", f"{d}/o.csv"],
        ["ur10e"], files={**ctl, "station.toml": config_with("robot.type", "ur10e")})

    # ---------------------------------------------------------------- synth
    sy = ["synth", "--poses", "12", "--validation", "3", "--out-dir", f"{d}/synth-out"]
    add("synth", "--robot=ur99", [*sy, "--robot", "ur99"], ["ur99"])
    numbers("synth", sy, "--poses", (*BAD_COUNTS, "1000000000"))
    numbers("synth", sy, "--validation", ("-1", "abc", "1000000000"))
    numbers("synth", sy, "--noise", ("-1", "nan", "inf", "1e308", "1", "abc"))
    numbers("synth", sy, "--seed", ("-1", "abc"))
    bad_json("synth", lambda p: [*sy, "--truth", p], "--truth", "truth.json")
    add("synth", "--truth=model-not-truth", [*sy, "--truth", f"{d}/model.json"], ["model.json"])
    add("synth", "--robot=ur10e-vs-ur5e-truth", [*sy, "--robot", "ur10e", "--truth", f"{d}/truth.json"],
        ["ur10e", "ur5e"])
    add("synth", "--out-dir=a-file", ["synth", "--poses", "12", "--validation", "3", "--out-dir",
                                      f"{d}/model.json"], ["model.json"])
    add("synth", "--out-dir=holds-the---truth", ["synth", "--poses", "12", "--validation", "3", "--truth",
                                                 f"{d}/truth.json", "--out-dir", d], ["truth.json"])
    add("synth", "--rigid-with---truth", [*sy, "--rigid", "--truth", f"{d}/truth.json"],
        ["--rigid", "--truth"])

    # ---------------------------------------------------------------- select
    se = ["select", "--robot", "ur5e", "--count", "12", "--candidates", "100", "--method", "random",
          "--quiet", "--no-bound", "--out", f"{d}/poses.json"]
    add("select", "--robot=ur99", [*se, "--robot", "ur99"], ["ur99"])
    for v in ("x", "1,2", "-2", "500"):
        add("select", f"--payload={v}", [*se, "--compliance", f"--payload={v}"], ["--payload"])
    numbers("select", se, "--count", (*BAD_COUNTS, "1000000000"))
    numbers("select", se, "--candidates", (*BAD_COUNTS, "1000000000"))
    numbers("select", se, "--seed", ("-1", "abc"))
    add("select", "--index=O9", [*se, "--index", "O9"], ["--index|O9"])
    add("select", "--method=magic", [*se, "--method", "magic"], ["--method|magic"])
    add("select", "--scaling=weird", [*se, "--scaling", "weird"], ["--scaling|weird"])
    for v in ("1,2", "nan,0,0", "1e308,0,0", "abc"):
        add("select", f"--tracker={v}", [*se, f"--tracker={v}"], ["--tracker"])
    for v in ("10,0,0", "nan,0,0", "1,2"):
        add("select", f"--smr={v}", [*se, f"--smr={v}"], ["--smr"])
    for v in ("1,2,3", "1,1,1,0,0,0", "nan,0,0,1,1,1", "-1e308,-1,0,1e308,1,1"):
        add("select", f"--keep-in={v}", [*se, f"--keep-in={v}"], ["--keep-in"])
    numbers("select", se, "--floor", ("nan", "inf", "1e308", "-1e308", "abc"))
    for v in ("5,1", "-1,2", "0,0", "nan,1", "1"):
        add("select", f"--range={v}", [*se, f"--range={v}"], ["--range"])
    numbers("select", se, "--half-angle", ("-1", "0", "90", "180", "nan", "1e308"))
    numbers("select", se, "--wrist-margin", ("-1", "180", "nan"))
    numbers("select", se, "--elbow-margin", ("-1", "180", "nan"))
    numbers("select", se, "--shoulder-margin", ("-1", "nan", "1e308"))
    add("select", "--disable=gravity", [*se, "--disable", "gravity"], ["--disable|gravity"])
    ta = [*se[:se.index("--method")], "--method", "time-aware", *se[se.index("--method") + 2:]]
    numbers("select", ta, "--budget", ("0", "-1", "nan", "inf", "1e308", "abc"))
    numbers("select", ta, "--speed", ("0", "-1", "4", "nan", "abc"))
    numbers("select", ta, "--acceleration", ("0", "-1", "41", "nan", "abc"))
    numbers("select", ta, "--dwell", ("-1", "1e308", "nan", "abc"))
    numbers("select", ta, "--time-limit", ("0", "-1", "1e308", "nan", "abc"))
    add("select", "--budget-without-time-aware", [*se, "--budget", "100"], ["--budget"])
    add("select", "--dwell-without-time-aware", [*se, "--dwell", "1"], ["--dwell"])
    add("select", "--budget-too-small", [*ta, "--budget", "1"], ["budget"])
    add("select", "--prune-with-time-aware", [*ta, "--prune"], ["--prune"])
    for v in ("1e300,0,0,0,0,0", "20,0,0,0,0,0", "nan,0,0,0,0,0", "1,2,3"):
        add("select", f"--start={v}", [*se, f"--start={v}"], ["--start"])
    add("select", "--out=directory", [*se, "--out", f"{d}/sub"], ["/sub"])

    # ---------------------------------------------------------------- sim
    add("sim", "--robot=ur99", ["sim", "--robot", "ur99"], ["ur99"])
    for v in ("not an address", "10.0.0.1", "127.0.0.256", ""):
        add("sim", f"--address={v or 'empty'}", ["sim", "--address", v], ["--address"])
    numbers("sim", ["sim"], "--speed", BAD_FLOATS)
    numbers("sim", ["sim"], "--control-port", ("99999", "-1", "65536", "abc"))
    numbers("sim", ["sim"], "--speed-slider", ("2", "-0.5", "nan"))
    numbers("sim", ["sim"], "--encoder-noise", ("-1", "nan", "inf", "1"))
    numbers("sim", ["sim"], "--seed", ("-1",))
    numbers("sim", ["sim"], "--baud", ("0", "-1", "abc"))
    numbers("sim", ["sim"], "--acceptance-angle", ("-1", "0", "90", "180", "nan"))
    for v in ("5.15", "x.y.z.w"):
        add("sim", f"--polyscope={v}", ["sim", "--polyscope", v], ["--polyscope"])
    add("sim", "--fault=meteor", ["sim", "--fault", "meteor"], ["--fault"])
    add("sim", "--truth:missing", ["sim", "--truth", f"{d}/none.json"], ["none.json"])
    add("sim", "--truth:garbage", ["sim", "--truth", f"{d}/g.json"], ["g.json"], files={"g.json": "{nope"})
    add("sim", "--truth:model-not-truth", ["sim", "--truth", f"{d}/model.json"], ["model.json"])
    add("sim", "--robot=ur10e-vs-ur5e-truth", ["sim", "--robot", "ur10e", "--truth", f"{d}/truth.json"],
        ["ur10e", "ur5e"])

    # ---------------------------------------------------------------- history
    hi = ["history", "--db"]
    numbers("history", [*hi, f"{d}/store.db"], "--limit", ("0", "-1", "abc", "1e9"))
    add("history", "--db:missing", [*hi, f"{d}/none.db"], ["none.db"])
    add("history", "--db:directory", [*hi, f"{d}/sub"], ["/sub"])
    add("history", "--db:empty-file", [*hi, f"{d}/empty.db"], ["empty.db"], files={"empty.db": ""})
    add("history", "--db:garbage", [*hi, f"{d}/g.db"], ["g.db"], files={"g.db": "hello\n" * 1000})
    add("history", "--db:binary", [*hi, f"{d}/b.db"], ["b.db"], files={"b.db": BINARY})
    add("history", "--db:a-json-file", [*hi, f"{d}/truth.json"], ["truth.json"])
    add("history", "--db:corrupt-mid-file", [*hi, f"{d}/corrupt.db"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})
    add("history", "--db:truncated", [*hi, f"{d}/cut.db"], ["cut.db"], files={"cut.db": truncated_store})
    add("history", "--db:newer-schema", [*hi, f"{d}/newer.db"], ["newer.db"], files={"newer.db": newer_store})
    add("history", "--db:not-a-hil-store", [*hi, f"{d}/photos.db"], ["photos.db"],
        files={"photos.db": foreign_sqlite})
    add("history", "HIL_DB=directory", ["history"], ["/sub"], env={"HIL_DB": f"{d}/sub"})
    add("history", "HIL_DB=missing", ["history"], ["none.db"], env={"HIL_DB": f"{d}/none.db"})
    add("history", "default-store-missing", ["history"], ["hil.db"])
    add("history", "--config:garbage", ["history", "--config", f"{d}/g.toml"], ["g.toml"],
        files={"g.toml": "[[[ nope"})
    add("history", "--config:missing", ["history", "--config", f"{d}/none.toml"], ["none.toml"])
    add("history", "--config:store.path-number", ["history", "--config", f"{d}/bad.toml"], ["store.path"],
        files={"bad.toml": config_with("store.path", 5)})
    add("history", "--db:read-only-media", [*hi, f"{d}/ro/store.db"], [], expect=0,
        files={"ro/store.db": lambda d: (d / "store.db").read_bytes()}, read_only=("ro/store.db", "ro"))

    # ---------------------------------------------------------------- show
    sh = ["show", "last", "--db", f"{d}/store.db"]
    add("show", "--export-measurements=the-store", [*sh, "--export-measurements", f"{d}/store.db"],
        ["store.db"])
    add("show", "--export-model=the-store", [*sh, "--export-model", f"{d}/store.db"], ["store.db"])
    add("show", "--export-measurements=the-store-relative", [*sh, "--export-measurements", "store.db"],
        ["store.db"])
    add("show", "--export-model=the-store-via-HIL_DB", ["show", "last", "--export-model", f"{d}/store.db"],
        ["store.db"], env={"HIL_DB": f"{d}/store.db"})
    add("show", "--export-model=the-config", ["show", "last", "--config", f"{d}/st.toml", "--export-model",
                                              f"{d}/st.toml"], ["st.toml"],
        files={"st.toml": config_with("store.path", "store.db")})
    add("show", "--export-model=--export-measurements", [*sh, "--export-model", f"{d}/same.out",
                                                         "--export-measurements", f"{d}/same.out"],
        ["same.out"])
    add("show", "--export-model=directory", [*sh, "--export-model", f"{d}/sub"], ["/sub"])
    add("show", "--export-measurements=directory", [*sh, "--export-measurements", f"{d}/sub"], ["/sub"])
    add("show", "--format-without-export", [*sh, "--format", "urdf"], ["--format"])
    add("show", "--format=sdf", [*sh, "--export-model", f"{d}/m.x", "--format", "sdf"], ["--format"])
    add("show", "--role=bystander", [*sh, "--export-measurements", f"{d}/m.csv", "--role", "bystander"],
        ["--role"])
    add("show", "ID=unknown", ["show", "nope", "--db", f"{d}/store.db"], ["nope"])
    add("show", "ID=empty", ["show", "", "--db", f"{d}/store.db"], ["ID|campaign"])
    add("show", "ID=last-of-an-empty-store", ["show", "last", "--db", f"{d}/empty-store.db"],
        ["empty-store.db|no campaign"], files={"empty-store.db": empty_store})
    add("show", "--db:missing", ["show", "last", "--db", f"{d}/none.db"], ["none.db"])
    add("show", "--db:empty-file", ["show", "last", "--db", f"{d}/empty.db"], ["empty.db"],
        files={"empty.db": ""})
    add("show", "--db:corrupt-mid-file", ["show", "last", "--db", f"{d}/corrupt.db"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})
    add("show", "--db:directory", ["show", "last", "--db", f"{d}/sub"], ["/sub"])
    add("show", "--db:read-only-media", ["show", "last", "--db", f"{d}/ro/store.db"], [], expect=0,
        files={"ro/store.db": lambda d: (d / "store.db").read_bytes()}, read_only=("ro/store.db", "ro"))

    # ---------------------------------------------------------------- robots
    ro = ["robots", "--db"]
    add("robots", "--db:missing", [*ro, f"{d}/none.db"], ["none.db"])
    add("robots", "--db:directory", [*ro, f"{d}/sub"], ["/sub"])
    add("robots", "--db:empty-file", [*ro, f"{d}/empty.db"], ["empty.db"], files={"empty.db": ""})
    add("robots", "--db:garbage", [*ro, f"{d}/g.db"], ["g.db"], files={"g.db": "hello\n" * 1000})
    add("robots", "--db:binary", [*ro, f"{d}/b.db"], ["b.db"], files={"b.db": BINARY})
    add("robots", "--db:corrupt-mid-file", [*ro, f"{d}/corrupt.db"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})
    add("robots", "--db:newer-schema", [*ro, f"{d}/newer.db"], ["newer.db"], files={"newer.db": newer_store})
    add("robots", "--db:not-a-hil-store", [*ro, f"{d}/photos.db"], ["photos.db"],
        files={"photos.db": foreign_sqlite})
    add("robots", "--station=unknown", [*ro, f"{d}/store.db", "--station", "cell-9"], ["--station", "cell-9"])
    add("robots", "HIL_DB=missing", ["robots"], ["none.db"], env={"HIL_DB": f"{d}/none.db"})
    add("robots", "default-store-missing", ["robots"], ["hil.db"])
    add("robots", "--config:garbage", ["robots", "--config", f"{d}/g.toml"], ["g.toml"],
        files={"g.toml": "[[[ nope"})
    add("robots", "--config:missing", ["robots", "--config", f"{d}/none.toml"], ["none.toml"])
    add("robots", "--db:read-only-media", [*ro, f"{d}/ro/store.db"], [], expect=0,
        files={"ro/store.db": lambda d: (d / "store.db").read_bytes()}, read_only=("ro/store.db", "ro"))

    # ---------------------------------------------------------------- robot
    rb = ["robot", "20235500001", "--db", f"{d}/store.db"]
    add("robot", "SERIAL=unknown", ["robot", "999", "--db", f"{d}/store.db"], ["999"])
    add("robot", "SERIAL=unknown-while-marking",
        ["robot", "999", "--db", f"{d}/store.db", "--mark-bad", "last", "--reason", "r"], ["999"])
    add("robot", "--mark-bad-without-reason", [*rb, "--mark-bad", "last"], ["--reason"])
    add("robot", "--mark-good-without-reason", [*rb, "--mark-good", "last"], ["--reason"])
    add("robot", "--reason=blank", [*rb, "--mark-bad", "last", "--reason", "  "], ["--reason"])
    add("robot", "--reason-without-mark", [*rb, "--reason", "why"], ["--reason"])
    add("robot", "--mark-bad=unknown", [*rb, "--mark-bad", "nope", "--reason", "r"], ["nope"])
    add("robot", "--mark-bad=empty", [*rb, "--mark-bad", "", "--reason", "r"], ["--mark-bad", "empty"])
    add("robot", "--mark-bad-and-good", [*rb, "--mark-bad", "last", "--mark-good", "last", "--reason", "r"],
        ["--mark-good|--mark-bad"])
    add("robot", "--format-without-export", [*rb, "--format", "urdf"], ["--format"])
    add("robot", "--export-model=the-store", [*rb, "--export-model", f"{d}/store.db"], ["store.db"])
    add("robot", "--export-model=directory", [*rb, "--export-model", f"{d}/sub"], ["/sub"])
    add("robot", "--export-model=missing-folder", [*rb, "--export-model", f"{d}/none/m.json"], ["none"])
    numbers("robot", rb, "--sigmas", BAD_FLOATS)
    add("robot", "--db:missing", ["robot", "20235500001", "--db", f"{d}/none.db"], ["none.db"])
    add("robot", "--db:missing-while-marking", ["robot", "20235500001", "--db", f"{d}/none.db", "--mark-bad",
                                                "last", "--reason", "r"], ["none.db"])
    add("robot", "--db:read-only-media", ["robot", "20235500001", "--db", f"{d}/ro/store.db"], [], expect=0,
        files={"ro/store.db": lambda d: (d / "store.db").read_bytes()}, read_only=("ro/store.db", "ro"))

    # ---------------------------------------------------------------- fleet-report
    fr = ["fleet-report", "--db", f"{d}/store.db", "--out", f"{d}/fleet.html"]
    add("fleet-report", "--out-missing", ["fleet-report", "--db", f"{d}/store.db"], ["--out"])
    add("fleet-report", "--out=the-store",
        ["fleet-report", "--db", f"{d}/store.db", "--out", f"{d}/store.db"], ["store.db"])
    add("fleet-report", "--out=the-store-via-HIL_DB", ["fleet-report", "--out", f"{d}/store.db"],
        ["store.db"], env={"HIL_DB": f"{d}/store.db"})
    add("fleet-report", "--out=the-config", ["fleet-report", "--config", f"{d}/st.toml", "--out",
                                             f"{d}/st.toml"], ["st.toml"],
        files={"st.toml": config_with("store.path", "store.db")})
    add("fleet-report", "--out=directory", ["fleet-report", "--db", f"{d}/store.db", "--out", f"{d}/sub"],
        ["/sub"])
    add("fleet-report", "--out=missing-folder", ["fleet-report", "--db", f"{d}/store.db", "--out",
                                                 f"{d}/none/fleet.html"], ["none"])
    for v in ("2024-13-01", "yesterday", "", "2024-02-30"):
        add("fleet-report", f"--since={v or 'empty'}", [*fr, "--since", v], ["--since"])
    numbers("fleet-report", fr, "--sigmas", ("0", "-1", "nan", "inf", "abc"))
    add("fleet-report", "--db:missing", ["fleet-report", "--db", f"{d}/none.db", "--out", f"{d}/fleet.html"],
        ["none.db"])
    add("fleet-report", "--db:garbage", ["fleet-report", "--db", f"{d}/g.db", "--out", f"{d}/fleet.html"],
        ["g.db"], files={"g.db": "hello\n" * 1000})
    add("fleet-report", "--db:corrupt-mid-file", ["fleet-report", "--db", f"{d}/corrupt.db", "--out",
                                                  f"{d}/fleet.html"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})

    # ---------------------------------------------------------------- report
    rep = ["report", "--result", f"{d}/result.json"]
    bad_json("report", lambda p: ["report", "--result", p, "--out", f"{d}/r.html"], "--result", "result.json")
    for ident_, path, value in (("validation-number", ["validation"], 1),
                                ("passed-string", ["passed"], "yes"),
                                ("accept_rms-negative", ["accept_rms"], -1.0),
                                ("model-missing", ["model"], DELETE),
                                ("model-geometry-1e308", ["model", "joints", 1, "xyz"], [1e308, 0, 0])):
        add("report", f"--result:{ident_}", ["report", "--result", f"{d}/{ident_}.json", "--out",
                                             f"{d}/r.html"],
            [f"{ident_}.json"], files={f"{ident_}.json": json_with("result.json", path, value)})
    add("report", "--out=--result", [*rep, "--out", f"{d}/result.json"], ["result.json"])
    add("report", "--out=directory", [*rep, "--out", f"{d}/sub"], ["/sub"])

    # ---------------------------------------------------------------- moveb plan
    mp = ["moveb", "plan", f"{d}/square.moveb", "--out", f"{d}/s.csv"]
    bad_program("moveb-plan", lambda p: ["moveb", "plan", p, "--out", f"{d}/s.csv"])
    numbers("moveb-plan", mp, "--step", ("1e-9", "0", "-1", "nan", "inf", "1e308"))
    numbers("moveb-plan", mp, "--velocity", ("1e30", "0", "-1", "nan", "inf"))
    numbers("moveb-plan", mp, "--acceleration", ("1e30", "0", "-1", "nan"))
    numbers("moveb-plan", mp, "--jerk", ("0", "-1", "nan", "1e308"))
    numbers("moveb-plan", mp, "--normal-acceleration", ("0", "-1", "nan"))
    numbers("moveb-plan", mp, "--rate", ("0", "-1", "nan", "inf", "1e308"))
    add("moveb-plan", "--continuity=G9", [*mp, "--continuity", "G9"], ["--continuity"])
    add("moveb-plan", "--out=PROGRAM", ["moveb", "plan", f"{d}/square.moveb", "--out", f"{d}/square.moveb"],
        ["square.moveb"])
    add("moveb-plan", "--out=directory", ["moveb", "plan", f"{d}/square.moveb", "--out", f"{d}/sub"],
        ["/sub"])

    # ---------------------------------------------------------------- moveb run
    mr = ["moveb", "run", f"{d}/square.moveb", "--sim", "--out", f"{d}/run.json"]
    bad_program("moveb-run", lambda p: ["moveb", "run", p, "--sim", "--out", f"{d}/run.json"])
    numbers("moveb-run", mr, "--velocity", ("1e30", "0", "-1", "nan"))
    numbers("moveb-run", mr, "--acceleration", ("0", "nan"))
    numbers("moveb-run", mr, "--jerk", ("0", "nan"))
    numbers("moveb-run", mr, "--normal-acceleration", ("0", "nan"))
    numbers("moveb-run", mr, "--joint-speed", ("0", "2", "nan"))
    numbers("moveb-run", mr, "--joint-acceleration", ("0", "-1", "nan", "inf"))
    numbers("moveb-run", mr, "--tracker-rate", ("0", "-1", "nan", "inf", "1e308"))
    numbers("moveb-run", mr, "--min-coverage", ("0", "1.5", "nan"))
    numbers("moveb-run", mr, "--speed", ("0", "-1", "nan", "inf", "1e308"))
    numbers("moveb-run", mr, "--seed", ("-1",))
    add("moveb-run", "--robot=ur99", [*mr, "--robot", "ur99"], ["ur99"])
    add("moveb-run", "--frame=moon", [*mr, "--frame", "moon"], ["--frame"])
    add("moveb-run", "--ik=magic", [*mr, "--ik", "magic"], ["--ik"])
    bad_json("moveb-run", lambda p: [*mr, "--model", p], "--model", "model.json")
    add("moveb-run", "--truth:missing", [*mr, "--truth", f"{d}/none.json"], ["none.json"])
    add("moveb-run", "--truth:deep-nesting", [*mr, "--truth", f"{d}/deep.json"], ["deep.json"],
        files={"deep.json": lambda d: DEEP_JSON})
    add("moveb-run", "--truth:model-not-truth", [*mr, "--truth", f"{d}/model.json"], ["model.json"])
    add("moveb-run", "--out=PROGRAM", [*mr[:-2], "--out", f"{d}/square.moveb"], ["square.moveb"])
    add("moveb-run", "--out=--model", [*mr[:-2], "--model", f"{d}/model.json", "--out", f"{d}/model.json"],
        ["model.json"])
    add("moveb-run", "--out=directory", [*mr[:-2], "--out", f"{d}/sub"], ["/sub"])
    add("moveb-run", "--plot=--model", [*mr, "--model", f"{d}/model.json", "--plot", f"{d}/model.json"],
        ["model.json"])
    add("moveb-run", "--plot=directory", [*mr, "--plot", f"{d}/sub"], ["/sub"])
    add("moveb-run", "--plot=--out", [*mr, "--plot", f"{d}/run.json"], ["run.json"])
    add("moveb-run", "--config-with---truth", ["moveb", "run", f"{d}/square.moveb", "--config",
                                               f"{d}/station.toml", "--truth", f"{d}/truth.json"],
        ["--truth"])
    bad_configs("moveb-run", lambda p: ["moveb", "run", f"{d}/square.moveb", "--config", p],
                keys=CONFIG_SUBSET, files_too=False)
    add("moveb-run", "config:empty-file-no-tracker-url", ["moveb", "run", f"{d}/square.moveb", "--config",
                                                          f"{d}/empty.toml"], ["tracker.url"],
        files={"empty.toml": ""})
    add("moveb-run", "--robot=ur10e-vs-ur5e-model", ["moveb", "run", f"{d}/square.moveb", "--sim", "--robot",
                                                     "ur10e", "--model", f"{d}/model.json", "--speed", "20"],
        ["ur10e", "ur5e"], station=True, timeout=60)
    add("moveb-run", "--robot=ur10e-vs-ur5e-truth", ["moveb", "run", f"{d}/square.moveb", "--sim", "--robot",
                                                     "ur10e", "--truth", f"{d}/truth.json", "--speed", "20"],
        ["ur10e", "ur5e"], station=True, timeout=60)
    add("moveb-run", "config:robot.type=ur10e-vs-UR5e-controller",
        ["moveb", "run", f"{d}/square.moveb", "--config", f"{d}/sim.toml", "--frame", "base"],
        ["ur10e", "ur5e"], files={"sim.toml": _sim_config("ur10e")}, station=True, timeout=60)

    # ---------------------------------------------------------------- tui
    tu = ["tui", "--sim", "--db", f"{d}/tui.db"]
    numbers("tui", tu, "--speed", ("0", "-1", "nan", "inf", "1e308"))
    numbers("tui", tu, "--seed", ("-1",))
    numbers("tui", tu, "--poses", ("-1", "0", "3", "100000000"))
    numbers("tui", tu, "--validation", ("0", "100000000"))
    numbers("tui", tu, "--candidates", ("0", "1000000000"))
    numbers("tui", tu, "--accept", ("-1", "nan", "0.1"))
    add("tui", "--robot=ur99", [*tu, "--robot", "ur99"], ["ur99"])
    add("tui", "--robot=ur10e-vs-ur5e-truth", [*tu, "--robot", "ur10e", "--truth", f"{d}/truth.json"],
        ["ur10e", "ur5e"])
    add("tui", "--truth:garbage", [*tu, "--truth", f"{d}/g.json"], ["g.json"], files={"g.json": "{nope"})
    add("tui", "--truth:xyz-true", [*tu, "--truth", f"{d}/t.json"], ["t.json"],
        files={"t.json": json_with("truth.json", ["joints", 1, "xyz"], [True, 0, 0])})
    add("tui", "--out-dir=a-file", [*tu, "--out-dir", f"{d}/model.json"], ["model.json"])
    add("tui", "--db=directory", ["tui", "--sim", "--db", f"{d}/sub"], ["/sub"])
    add("tui", "--db=corrupt-mid-file", ["tui", "--sim", "--db", f"{d}/corrupt.db"], ["corrupt.db"],
        files={"corrupt.db": corrupt_store})
    # (No "--db=empty-file" case: the TUI writes the store; see calibrate's note on 0-byte files.)
    bad_configs("tui", lambda p: ["tui", "--config", p, "--db", f"{d}/tui.db"], keys=CONFIG_SUBSET,
                files_too=False)
    add("tui", "config:garbage", ["tui", "--config", f"{d}/g.toml"], ["g.toml"], files={"g.toml": "[[[ nope"})
    add("tui", "config:empty-file-no-tracker-url", ["tui", "--config", f"{d}/empty.toml", "--db",
                                                    f"{d}/tui.db"], ["tracker.url"], files={"empty.toml": ""})

    # ---------------------------------------------------------------- issue 31: classes of bad surroundings
    # ids "c<class>-..." (bench/adversarial.py prints them per class)
    idf = ["identify", "--robot", "ur5e", "--out", f"{d}/m-out.json", "--measurements"]
    for dev in ("/dev/zero", "/dev/urandom"):
        add("identify", f"c1-measurements={dev}", [*idf, dev], [dev])
        add("validate", f"c1-measurements={dev}", ["validate", "--model", f"{d}/model.json", "--measurements",
                                                   dev], [dev])
    add("identify", "c1-measurements=fifo", [*idf, f"{d}/pipe"], ["pipe", "fifo"], fifos=("pipe",))
    add("fk", "c1-joints=fifo", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/pipe", "--out",
                                 f"{d}/p-out.csv"], ["pipe"], fifos=("pipe",))
    add("fk", "c1-model=/dev/zero", ["fk", "--model", "/dev/zero", "--joints", f"{d}/joints.csv", "--out",
                                     f"{d}/p-out.csv"], ["/dev/zero"])
    add("export", "c1-model=fifo", ["export", "--model", f"{d}/pipe", "--format", "urdf", "--out",
                                    f"{d}/x.urdf"], ["pipe"], fifos=("pipe",))
    add("compensate", "c1-input=fifo", ["compensate", "--model", f"{d}/model.json", "--config",
                                        f"{d}/station.toml", f"{d}/pipe", "--out", f"{d}/c-out.csv"],
        ["pipe"], fifos=("pipe",))
    add("calibrate", "c1-config=/dev/urandom", ["calibrate", "--config", "/dev/urandom", "--db",
                                               f"{d}/cal.db"], ["/dev/urandom"])
    add("calibrate", "c1-config=fifo", ["calibrate", "--config", f"{d}/pipe", "--db", f"{d}/cal.db"],
        ["pipe"], fifos=("pipe",))
    add("moveb-plan", "c1-program=fifo", ["moveb", "plan", f"{d}/pipe", "--out", f"{d}/s.csv"], ["pipe"],
        fifos=("pipe",))
    rows100k = "\n".join("0.1,-1.2,1.3,-1.4,1.5,0.6,1.1,0.2,0.3" for _ in range(100_000))
    add("identify", "c1-measurements=100000-rows", [*idf, f"{d}/big.csv"], ["big.csv", "10000"],
        files={"big.csv": "q1,q2,q3,q4,q5,q6,x,y,z\n" + rows100k + "\n"})
    add("validate", "c1-measurements=100000-rows",
        ["validate", "--model", f"{d}/model.json", "--measurements", f"{d}/big.csv"], ["big.csv", "10000"],
        files={"big.csv": "q1,q2,q3,q4,q5,q6,x,y,z\n" + rows100k + "\n"})
    add("compensate", "c1-input=100000-rows",
        ["compensate", "--model", f"{d}/model.json", "--config", f"{d}/station.toml", f"{d}/big.csv", "--out",
         f"{d}/c-out.csv"], ["big.csv", "10000"],
        files={"big.csv": "x,y,z,rx,ry,rz\n" + "\n".join("0.4,0.1,0.3,0,3.1,0" for _ in range(100_000))})

    idm = ["identify", "--robot", "ur5e", "--measurements", f"{d}/measurements.csv", "--out"]
    long_name = "a" * 300 + ".json"
    for target in ("/dev/full", "/dev/null"):
        add("identify", f"c2-out={target}", [*idm, target], ["--out", target])
        add("export", f"c2-out={target}", ["export", "--model", f"{d}/model.json", "--format", "json",
                                           "--out", target], ["--out", target])
    add("identify", "c2-out=trailing-slash", [*idm, f"{d}/newout.json/"], ["--out", "slash"])
    add("identify", "c2-out=300-char-name", [*idm, f"{d}/{long_name}"], ["--out", "255"])
    add("identify", "c2-out=fifo", [*idm, f"{d}/pipe"], ["--out", "fifo"], fifos=("pipe",))
    add("synth", "c2-out-dir=300-char-name", ["synth", "--poses", "12", "--out-dir", f"{d}/{long_name}"],
        ["--out-dir", "255"])
    add("fk", "c2-out=/dev/full", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/joints.csv", "--out",
                                   "/dev/full"], ["--out", "/dev/full"])
    add("report", "c2-out=trailing-slash", ["report", "--result", f"{d}/result.json", "--out",
                                            f"{d}/r.html/"], ["--out", "slash"])
    sel = ["select", "--robot", "ur5e", "--count", "10", "--candidates", "500"]
    add("select", "c2-stdout=full", sel, ["stdout", "no space"], stdout="full", timeout=60)
    add("select", "c2-stdout=closed", sel, ["stdout", "closed"], stdout="closed", timeout=60)
    add("show", "c2-stdout=full", ["show", "last", "--db", f"{d}/store.db"], ["stdout"], stdout="full")
    add("show", "c2-stdout=closed", ["show", "last", "--db", f"{d}/store.db"], ["stdout"], stdout="closed")

    with_cube = {**BASE_CONFIG, "verify": {"centre": [0.4, 0.0, 0.4], "edge": 0.2}}
    for cmd in ("calibrate", "verify"):
        cfg = [cmd, "--config", f"{d}/bad.toml", "--db", f"{d}/c.db"]
        base = with_cube if cmd == "verify" else BASE_CONFIG
        for label, url in (("http", "http://tracker:80"), ("spy-empty", "spy://"),
                           ("port-99999", "socket://tracker:99999"), ("socket-no-port", "socket://tracker"),
                           ("rfc2217-no-host", "rfc2217://"), ("port-not-number", "socket://tracker:x")):
            add(cmd, f"c4-tracker.url={label}", cfg, ["tracker.url"],
                files={"bad.toml": config_with("tracker.url", url, base)}, timeout=60)
        add(cmd, "c4-store.path=/proc", [cmd, "--config", f"{d}/bad.toml"], ["store.path", "/proc"],
            files={"bad.toml": config_with("store.path", "/proc/hil.db", base)}, timeout=60)
        add(cmd, "c4-config-with-seed", [cmd, "--config", f"{d}/station.toml", "--seed", "3", "--db",
                                         f"{d}/c.db"], ["--seed"], timeout=60)
    emscon = {**BASE_CONFIG, "tracker": {**BASE_CONFIG["tracker"], "protocol": "emscon"}}
    add("calibrate", "c4-tracker.url=emscon-serial-device",
        ["calibrate", "--config", f"{d}/bad.toml", "--db", f"{d}/c.db"], ["tracker.url"],
        files={"bad.toml": toml_text(emscon)})
    add("moveb-run", "c4-config-with-seed",
        ["moveb", "run", f"{d}/square.moveb", "--config", f"{d}/station.toml", "--seed", "3"], ["--seed"])
    add("tui", "c4-tracker.url=http", ["tui", "--config", f"{d}/bad.toml", "--db", f"{d}/c.db"],
        ["tracker.url"], files={"bad.toml": config_with("tracker.url", "http://tracker")})
    add("select", "c4-tracker-at-the-base", [*sel, "--tracker", "0,0,0"], ["--tracker"])
    # requests no candidate can meet, at the default 20,000 candidates (drawn 2,000,000 vectors: 15-35 s):
    # geometry refuses them before any draw; the last falls back to sampling, whose bound is its own
    empty = ["select", "--robot", "ur5e", "--count", "30"]
    for label, extra, names in (
            ("tracker-inside-the-base", ["--tracker", "0.03,-0.02,0.12"], ["--tracker", "base"]),
            ("tracker-beyond-the-range", ["--tracker", "20,0,0", "--range", "0.8,2"], ["--tracker", "range"]),
            ("tracker-within-the-range-min", ["--tracker", "0,0,0.3", "--range", "3,20"],
             ["--tracker", "range"]),
            ("keep-in-out-of-reach", ["--keep-in", "3,3,3,4,4,4"], ["--keep-in", "reach"]),
            ("floor-above-the-shoulder", ["--floor", "1.5"], ["--floor"]),
            ("singularity-margins-leave-nothing", ["--wrist-margin", "89.9", "--elbow-margin", "89.9"],
             ["--wrist-margin|--elbow-margin"])):
        add("select", f"c4-{label}", [*empty, *extra], names)
    add("select", "c4-time-aware-tracker-inside-the-base",
        [*empty, "--method", "time-aware", "--tracker", "0,0,0"], ["--tracker", "base"])
    for cmd in ("history", "robots"):
        add(cmd, "c4-store.url-not-a-url", [cmd, "--config", f"{d}/bad.toml"], ["store.url", "not a url"],
            files={"bad.toml": config_with("store.url", "dbhost:5432/hil")})
    # a store's location, wherever it is given (--db, $HIL_DB, store.url), is named with what is wrong:
    # no such file, no such folder either, not a URL (a URL with a typo was "no such database")
    for cmd, argv in (("history", ["history"]), ("robots", ["robots"]), ("show", ["show", "last"])):
        add(cmd, "c4-store.url-no-such-file", [*argv, "--config", f"{d}/bad.toml"],
            ["store.url", "gone.db", "no such database"],
            files={"bad.toml": config_with("store.url", "gone.db")})
        add(cmd, "c4-store.url-no-such-folder", [*argv, "--config", f"{d}/bad.toml"],
            ["store.url", "nofolder", "folder"],
            files={"bad.toml": config_with("store.url", "nofolder/x.db")})
        add(cmd, "c4-db-no-such-folder", [*argv, "--db", f"{d}/nofolder/x.db"],
            ["--db", "nofolder", "folder"])
        add(cmd, "c4-db-not-a-url", [*argv, "--db", "dbhost:5432/hil"], ["--db", "not a url"])
        add(cmd, "c4-HIL_DB-not-a-url", argv, ["$HIL_DB", "not a url"], env={"HIL_DB": "dbhost:5432/hil"})
        add(cmd, "c4-HIL_DB-no-such-file", argv, ["$HIL_DB", "gone.db", "no such database"],
            env={"HIL_DB": f"{d}/gone.db"})
        add(cmd, "c4-db-postgresql-without-a-host", [*argv, "--db", "postgresql:///hil"], ["--db", "host"])
        add(cmd, "c4-db-postgresql-port-0", [*argv, "--db", "postgresql://hil@127.0.0.1:0/hil"],
            ["--db", "port", "65535"])
        add(cmd, "c4-store.url-postgresql-port-99999", [*argv, "--config", f"{d}/bad.toml"],
            ["store.url", "port", "65535"],
            files={"bad.toml": config_with("store.url", "postgresql://hil@127.0.0.1:99999/hil")})
    for cmd in ("calibrate", "verify"):
        base = with_cube if cmd == "verify" else BASE_CONFIG
        add(cmd, "c4-store.url-no-such-folder", [cmd, "--config", f"{d}/bad.toml"],
            ["store.url", "nofolder", "folder"],
            files={"bad.toml": config_with("store.url", "nofolder/x.db", base)}, timeout=60)
        add(cmd, "c4-sim-db-no-such-folder", [cmd, "--sim", "--db", f"{d}/nofolder/x.db"],
            ["--db", "nofolder", "folder"], timeout=60)
        add(cmd, "c4-HIL_DB-not-a-url", [cmd, "--config", f"{d}/ok.toml"], ["$HIL_DB", "not a url"],
            files={"ok.toml": toml_text(base)}, env={"HIL_DB": "dbhost:5432/hil"}, timeout=60)

    damaged = {"config": ("UPDATE campaigns SET config = '{broken'", "campaigns"),
               "joints": ("UPDATE measurements SET q = '[1, 2' WHERE id = 3", "measurements"),
               "model": ("UPDATE models SET doc = 'nope'", "models"),
               "target": ("UPDATE poses SET target = '[' WHERE idx = 4", "poses")}
    for label, (sql, table) in damaged.items():
        files = {"dmg.db": damaged_store(sql)}
        add("show", f"c5-damaged-{label}", ["show", "last", "--db", f"{d}/dmg.db"], ["table " + table, "id"],
            files=files)
        add("history", f"c5-damaged-{label}-lists-the-rest", ["history", "--db", f"{d}/dmg.db"], [],
            files=files, expect=0)
        add("robots", f"c5-damaged-{label}-lists-the-rest", ["robots", "--db", f"{d}/dmg.db"], [],
            files=files, expect=0)
    # --resume on a store that cannot give one: refused before a simulated station starts (seconds)
    add("calibrate", "c5-r3-resume-damaged-unfinished-config",
        ["calibrate", "--sim", "--resume", "--db", f"{d}/dmg.db"], ["table campaigns"],
        files={"dmg.db": damaged_store("UPDATE campaigns SET config = '{broken', status = 'interrupted'")})
    add("calibrate", "c5-r3-resume-nothing-unfinished",
        ["calibrate", "--sim", "--resume", "--db", f"{d}/fin.db"], ["--resume", "fin.db", "unfinished"],
        files={"fin.db": damaged_store("UPDATE campaigns SET status = 'accepted'")})
    add("calibrate", "c5-r3-resume-no-store", ["calibrate", "--sim", "--resume", "--db", f"{d}/none.db"],
        ["--resume", "none.db"])
    add("show", "c5-damaged-joints-export", ["show", "last", "--db", f"{d}/dmg.db", "--export-measurements",
                                             f"{d}/m-out.csv"], ["table measurements"],
        files={"dmg.db": damaged_store(damaged["joints"][0])})

    comp = ["compensate", "--model", f"{d}/model.json", "--config", f"{d}/station.toml", "--out",
            f"{d}/c-out.txt"]
    for label, header in (("typo", "x,y,zz,rx,ry,rz"), ("other-names", "X_mm,Y_mm,Z_mm,A,B,C")):
        for suffix in ("txt", "dat"):
            add("compensate", f"c6-{suffix}-csv-header-{label}", [*comp, f"{d}/poses.{suffix}"],
                [f"poses.{suffix}", "x,y,z,rx,ry,rz"],
                files={f"poses.{suffix}": header + "\n0.4,0.1,0.3,0,3.1,0\n"})
    add("calibrate", "c6-ascii-error-with-a-unit", ["calibrate", "--config", f"{d}/bad.toml", "--db",
                                                    f"{d}/c.db"], ["tracker.temperature"],
        files={"bad.toml": config_with("tracker.temperature", -300.0)}, ascii=True)
    add("validate", "c6-ascii-model-out-of-range", ["validate", "--model", f"{d}/m.json", "--measurements",
                                                    f"{d}/validation.csv"], ["m.json"],
        files={"m.json": json_with("model.json", ["smr"], [10.0, 0.0, 0.0])}, ascii=True)
    add("history", "c6-ascii-listing", ["history", "--db", f"{d}/store.db"], [], expect=0, ascii=True)
    add("show", "c6-ascii-show", ["show", "last", "--db", f"{d}/store.db"], [], expect=0, ascii=True)

    # class 3: numbers that are not physical (hil.files.quantities: NaN, ±inf, denormals, out of range)
    tiny = "1e-320"  # a denormal: non-zero, below sys.float_info.min
    for label, pose in (("nan", "p[nan, 0, .3, 0, 3.14, 0]"), ("inf", "p[.4, inf, .3, 0, 3.14, 0]"),
                        ("denormal", f"p[.4, {tiny}, .3, 0, 3.14, 0]"),
                        ("rotation-1e6", "p[.4, 0, .3, 0, 1e6, 0]"),
                        ("rotation-degrees", "p[.4, 0, .3, 0, 180, 0]")):
        add("compensate", f"c3-urscript-{label}", [*co, f"{d}/p.script", "--out", f"{d}/o.script"],
            ["p.script:2"], files={**ctl, "p.script": f"def f():\n  movel({pose}, a=1.2)\nend\n"})
    for label, row, names in (("rotation-degrees", "0.4,0.1,0.3,0,180,0", ["degrees"]),
                              ("rotation-1e6", "0.4,0.1,0.3,0,1e6,0", ["rotation"]),
                              ("nan", "0.4,nan,0.3,0,3.1,0", []),
                              ("denormal", f"0.4,{tiny},0.3,0,3.1,0", [])):
        add("compensate", f"c3-pose-csv-{label}", [*co, f"{d}/t.csv", "--out", f"{d}/o.csv"],
            ["t.csv", "line 2", *names], files={**ctl, "t.csv": "x,y,z,rx,ry,rz\n" + row + "\n"})
    for cmd, argv_of in (("export", lambda f: ["export", "--model", f, "--format", "urdf", "--out",
                                               f"{d}/x.urdf"]),
                         ("validate", lambda f: ["validate", "--model", f, "--measurements",
                                                 f"{d}/validation.csv"])):
        for label, path, value, raw in (("flange-NaN", ["flange", "xyz"], None, "[NaN, 0, 0]"),
                                        ("flange-rpy-inf", ["flange", "rpy"], None, "[0, Infinity, 0]"),
                                        ("link-5m", ["joints", 2, "xyz"], [5.0, 0.0, 0.0], None),
                                        ("link-denormal", ["joints", 2, "xyz"], None, f"[{tiny}, 0, 0]"),
                                        ("rpy-degrees", ["joints", 1, "rpy"], [0.0, 90.0, 0.0], None)):
            add(cmd, f"c3-model-{label}", argv_of(f"{d}/m.json"), ["m.json", path[0]],
                files={"m.json": json_with("model.json", path, value, raw=raw)})
    add("synth", "c3-truth-noise-denormal", ["synth", "--truth", f"{d}/t.json", "--out-dir", f"{d}/o"],
        ["t.json", "noise"],
        files={"t.json": json_with("truth.json", ["noise", "encoder_sigma"], None, raw=tiny)})
    idc = ["identify", "--robot", "ur5e", "--measurements", f"{d}/measurements.csv", "--out",
           f"{d}/m-out.json",
           "--compliance", "--payload", "5,0,0,0.05"]
    add("identify", "c3-mounting-degrees", [*idc, "--mounting", "90,0,0"], ["--mounting", "degrees"])
    add("identify", "c3-mounting-nan", [*idc, "--mounting", "nan,0,0"], ["--mounting"])
    add("fk", "c3-payload-without-com", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/joints.csv",
                                         "--payload", "6", "--out", f"{d}/p.csv"], ["--payload", "centre"])
    add("fk", "c3-payload-com-denormal", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/joints.csv",
                                          "--payload", f"6,0,{tiny},0.05", "--out", f"{d}/p.csv"],
        ["--payload"])
    add("validate", "c3-max-rms-denormal", ["validate", "--model", f"{d}/model.json", "--measurements",
                                            f"{d}/validation.csv", "--max-rms", tiny], ["--max-rms"])
    add("select", "c3-time-limit-denormal", [*se, "--method", "time-aware", "--time-limit", tiny],
        ["--time-limit"])
    add("sim", "c3-speed-denormal", ["sim", "--speed", tiny], ["--speed"])
    for key in ("robot.acceleration", "campaign.stability", "tracker.timeout", "campaign.search_time"):
        add("calibrate", f"c3-{key}-denormal", ["calibrate", "--config", f"{d}/bad.toml", "--db",
                                                f"{d}/c.db"], [key],
            files={"bad.toml": config_with(key, Raw(tiny))})
    add("calibrate", "c3-robot.mounting-degrees", ["calibrate", "--config", f"{d}/bad.toml", "--db",
                                                   f"{d}/c.db"], ["robot.mounting", "degrees"],
        files={"bad.toml": config_with("robot.mounting", [90.0, 0.0, 0.0])})
    add("calibrate", "c3-tracker.temperature-nan", ["calibrate", "--config", f"{d}/bad.toml", "--db",
                                                    f"{d}/c.db"], ["tracker.temperature"],
        files={"bad.toml": config_with("tracker.temperature", Raw("nan"))})
    add("identify", "c3-measurements-denormal", [*idf, f"{d}/m.csv"], ["m.csv", "line 3"],
        files={"m.csv": csv_with("measurements.csv", 3, 7, tiny)})
    add("fk", "c3-joints-denormal", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/q.csv", "--out",
                                     f"{d}/p.csv"], ["q.csv", "line 3"],
        files={"q.csv": csv_with("joints.csv", 3, 2, tiny)})
    add("moveb-plan", "c3-program-denormal", ["moveb", "plan", f"{d}/p.moveb", "--out", f"{d}/s.csv"],
        ["p.moveb"], files={"p.moveb": moveb_line(f"MOVEB 500 -50 300  0 0 -1  1 0 0  0.5 {tiny}")})

    # ---------------------------------------------------------------- issue 31, second independent pass
    # ids "c<class>-r2-...": cases of a pass invented without reading this table (bench/adversarial.py
    # counts them apart). The first group failed before its fix; the rest passed and are kept so they stay so.
    from hil.files.inputs import MAX_LINE_CHARS, MAX_TEXT_LINES

    many_lines = "\n" * (MAX_TEXT_LINES + 1)  # 1 MB of nothing: the line count, not the size, refuses it
    long_line = "1," * (MAX_LINE_CHARS // 2 + 1)
    hdr = "q1,q2,q3,q4,q5,q6,x,y,z\n"
    ir2 = ["identify", "--robot", "ur5e", "--out", f"{d}/m-out.json", "--measurements"]
    # class 1, failed: files that end but whose lines or size kept a reader busy for minutes
    add("identify", "c1-r2-measurements=a-million-newlines", [*ir2, f"{d}/nl.csv"], ["nl.csv", "lines"],
        files={"nl.csv": hdr + many_lines})
    add("identify", "c1-r2-measurements=a-million-comment-lines", [*ir2, f"{d}/cm.csv"], ["cm.csv", "lines"],
        files={"cm.csv": hdr + "#\n" * (MAX_TEXT_LINES + 1)})
    add("identify", "c1-r2-measurements=one-line-of-half-a-million-fields", [*ir2, f"{d}/one.csv"],
        ["one.csv", "line 1", "characters"], files={"one.csv": "q1," + long_line + "\n"})
    add("moveb-plan", "c1-r2-program=a-million-newlines", ["moveb", "plan", f"{d}/nl.moveb", "--out",
                                                           f"{d}/s.csv"], ["nl.moveb", "lines"],
        files={"nl.moveb": many_lines})
    add("moveb-plan", "c1-r2-program=one-long-line", ["moveb", "plan", f"{d}/one.moveb", "--out",
        f"{d}/s.csv"],
        ["one.moveb", "line 1"], files={"one.moveb": "MOVEB " + long_line.replace(",", " ") + "\n"})
    add("calibrate", "c1-r2-config=over-1MiB", ["calibrate", "--config", f"{d}/big.toml", "--db",
        f"{d}/c.db"],
        ["big.toml", "1 MiB"], files={"big.toml": lambda dd: (dd / "station.toml").read_text()
                                      + "# " + "x" * (1 << 20) + "\n"})
    add("calibrate", "c1-r2-config=a-million-newlines", ["calibrate", "--config", f"{d}/nl.toml", "--db",
                                                         f"{d}/c.db"], ["nl.toml", "lines"],
        files={"nl.toml": lambda dd: (dd / "station.toml").read_text() + many_lines})
    add("compensate", "c1-r2-input=script-of-a-million-newlines",
        [*co, f"{d}/nl.script", "--out", f"{d}/o.script"], ["nl.script", "lines"],
        files={**ctl, "nl.script": "def f():\n" + many_lines + "end\n"})
    add("validate", "c1-r2-model=json-over-16MiB", ["validate", "--model", f"{d}/big.json", "--measurements",
                                                    f"{d}/validation.csv"], ["big.json", "16 MiB"],
        files={"big.json": "[" + "1," * (8 << 20) + "1]"})
    add("report", "c1-r2-result=fifo", ["report", "--result", f"{d}/pipe", "--out", f"{d}/r.html"],
        ["--result", "pipe", "FIFO"], fifos=("pipe",))
    add("verify", "c1-r2-model=fifo", ["verify", "--sim", "--model", f"{d}/pipe", "--db", f"{d}/v.db"],
        ["--model", "pipe"], fifos=("pipe",))
    add("sim", "c1-r2-truth=fifo", ["sim", "--truth", f"{d}/pipe"], ["--truth", "pipe"], fifos=("pipe",))
    add("fleet-report", "c1-r2-db=fifo", ["fleet-report", "--db", f"{d}/pipe", "--out", f"{d}/f.html"],
        ["--db", "pipe", "FIFO"], fifos=("pipe",))
    add("history", "c1-r2-db=/dev/zero", ["history", "--db", "/dev/zero"], ["--db", "/dev/zero", "device"])
    add("robots", "c1-r2-db=directory", ["robots", "--db", f"{d}/sub"], ["--db", "sub", "folder"])
    add("calibrate", "c1-r2-sim-db=fifo", ["calibrate", "--sim", "--db", f"{d}/pipe"], ["--db", "pipe"],
        fifos=("pipe",))
    # class 2, failed: a stdout that cannot take the result was found after the files were written
    add("identify", "c2-r2-stdout=full", [*ir2, f"{d}/measurements.csv"], ["stdout", "no space"],
        stdout="full")
    add("fk", "c2-r2-json-stdout=closed", ["fk", "--model", f"{d}/model.json", "--joints", f"{d}/joints.csv",
                                           "--out", f"{d}/p-out.csv", "--json"], ["stdout", "closed"],
        stdout="closed")
    add("validate", "c2-r2-stdout=full", ["validate", "--model", f"{d}/model.json", "--measurements",
                                          f"{d}/validation.csv"], ["stdout"], stdout="full")
    # class 5, failed: a table dropped by hand was a failed job (exit 1), not a damaged store
    add("show", "c5-r2-events-table-dropped", ["show", "last", "--db", f"{d}/dmg.db"], ["dmg.db", "events"],
        files={"dmg.db": damaged_store("DROP TABLE events")})
    add("robot", "c5-r2-damaged-model-export",
        ["robot", "20235500001", "--db", f"{d}/dmg.db", "--export-model", f"{d}/m-out.json"],
        ["table models", "id"],
        files={"dmg.db": damaged_store("UPDATE models SET doc = '{'")})
    # class 5: a number column holding text (SQLite keeps what is written) was an internal error (exit 70)
    for cmd, argv in (("show", ["show", "last"]), ("robots", ["robots"]), ("robot", ["robot", "20235500001"]),
                      ("history", ["history"])):
        add(cmd, "c5-r3-created-not-a-number", [*argv, "--db", f"{d}/dmg.db"],
            ["table campaigns", "created", "not a number"],
            files={"dmg.db": damaged_store("UPDATE campaigns SET created = 'abc'")})
    add("show", "c5-r3-measurement-time-not-a-number", ["show", "last", "--db", f"{d}/dmg.db"],
        ["table measurements", "t is not a number"],
        files={"dmg.db": damaged_store("UPDATE measurements SET t = 'x' WHERE id = 3")})
    # class 6, failed: an empty input, whose kind nothing tells, was "compensated" with no targets, exit 0
    for name in ("poses", "empty.script"):
        add("compensate", f"c6-r2-empty-input-{name}", [*co, f"{d}/{name}", "--out", f"{d}/o.csv"],
            [name, "empty"], files={**ctl, name: "\n  \n"})
    # passed before, kept
    add("identify", "c1-r2-controller=/dev/zero", [*ir2, f"{d}/measurements.csv", "--controller",
        "/dev/zero"],
        ["/dev/zero"])
    add("compensate", "c1-r2-input=/dev/zero", [*co, "/dev/zero", "--out", f"{d}/o.script"], ["/dev/zero"],
        files=ctl)
    add("synth", "c1-r2-truth=/dev/zero", ["synth", "--truth", "/dev/zero", "--out-dir", f"{d}/o"],
        ["/dev/zero"])
    add("tui", "c1-r2-config=fifo", ["tui", "--config", f"{d}/pipe"], ["pipe"], fifos=("pipe",))
    add("export", "c2-r2-out=same-as-model", ["export", "--model", f"{d}/model.json", "--format", "json",
                                              "--out", f"{d}/model.json"], ["--out", "--model"])
    add("fleet-report", "c2-r2-out=the-store", ["fleet-report", "--db", f"{d}/store.db", "--out",
                                                f"{d}/store.db"], ["--out", "store"])
    add("fleet-report", "c2-r2-out=through-a-file", ["fleet-report", "--db", f"{d}/store.db", "--out",
                                                     f"{d}/model.json/f.html"], ["--out", "not a directory"])
    add("moveb-plan", "c2-r2-out=fifo", ["moveb", "plan", f"{d}/square.moveb", "--out", f"{d}/pipe"],
        ["--out", "FIFO"], fifos=("pipe",))
    add("synth", "c2-r2-out-dir=a-file", ["synth", "--out-dir", f"{d}/model.json"], ["--out-dir",
        "model.json"])
    add("calibrate", "c2-r2-out-is-report", ["calibrate", "--sim", "--db", f"{d}/c.db", "--out",
        f"{d}/x.html",
                                             "--report", f"{d}/x.html"], ["--report", "--out"])
    add("compensate", "c3-r2-tcp-in-millimetres", [*co, f"{d}/t.csv", "--out", f"{d}/o.csv", "--tcp",
                                                   "0,0,100,0,0,0"], ["--tcp"],
        files={**ctl, "t.csv": "x,y,z,rx,ry,rz\n0.4,0.1,0.3,0,3.1,0\n"})
    add("compensate", "c3-r2-near-in-degrees", [*co, f"{d}/t.csv", "--out", f"{d}/o.csv", "--near",
                                                "0,-90,90,0,90,0"], ["--near"],
        files={**ctl, "t.csv": "x,y,z,rx,ry,rz\n0.4,0.1,0.3,0,3.1,0\n"})
    add("identify", "c3-r2-smr-in-millimetres", [*ir2, f"{d}/measurements.csv", "--smr", "0,0,45"], ["--smr"])
    add("moveb-plan", "c3-r2-step-denormal", ["moveb", "plan", f"{d}/square.moveb", "--out", f"{d}/s.csv",
                                              "--step", "1e-320"], ["--step"])
    add("fleet-report", "c3-r2-since-no-such-date", ["fleet-report", "--db", f"{d}/store.db", "--out",
                                                     f"{d}/f.html", "--since", "2026-13-45"], ["--since"])
    add("calibrate", "c4-r2-tracker.url=port-0", ["calibrate", "--config", f"{d}/bad.toml", "--db",
        f"{d}/c.db"],
        ["tracker.url"], files={"bad.toml": config_with("tracker.url", "socket://tracker:0")})
    add("calibrate", "c4-r2-config-with-truth", ["calibrate", "--config", f"{d}/station.toml", "--truth",
                                                 f"{d}/truth.json", "--db", f"{d}/c.db"], ["--truth"])
    add("calibrate", "c4-r2-sim-db=/proc", ["calibrate", "--sim", "--db", "/proc/hil-r2.db"], ["--db",
        "/proc"])
    add("show", "c5-r2-not-sqlite", ["show", "last", "--db", f"{d}/x.db"], ["x.db"],
        files={"x.db": "hello, this is not sqlite\n" * 100})
    add("compensate", "c6-r2-csv-suffix-holding-a-script", [*co, f"{d}/p.csv", "--out", f"{d}/o.csv"],
        ["p.csv"],
        files={**ctl, "p.csv": "def f():\n  movel(p[.4, 0, .3, 0, 3.14, 0], a=1.2)\nend\n"})

    # ---------------------------------------------------------------- the top level
    add("hil", "unknown-command", ["frobnicate"], ["frobnicate"])
    add("hil", "unknown-option", ["--frobnicate", "history"], ["--frobnicate"])

    seen: set[str] = set()
    for c in cases:
        assert c.name not in seen, f"duplicate case {c.name}"
        seen.add(c.name)
    return cases


#: Every key of hil/station/station.example.toml with a wrong type or an absurd value.
CONFIG_VALUES: tuple[tuple[str, Any], ...] = (
    ("station.name", 5),
    ("robot.type", 5), ("robot.type", "ur99"),
    ("robot.address", 5), ("robot.address", "not an address"), ("robot.address", ""),
    ("robot.speed", "fast"), ("robot.speed", 0), ("robot.speed", -1), ("robot.speed", 1e9),
    ("robot.speed", Raw("nan")),
    ("robot.acceleration", "x"), ("robot.acceleration", 0), ("robot.acceleration", 1e9),
    ("robot.settle_time", "x"), ("robot.settle_time", -1), ("robot.settle_time", 1e12),
    ("robot.settle", "quick"), ("robot.settle", 5),
    ("robot.settle_max", 0), ("robot.settle_max", -1), ("robot.settle_max", 1e12), ("robot.settle_max", "x"),
    ("robot.joint_samples", 2.5), ("robot.joint_samples", 0), ("robot.joint_samples", 1_000_000_000),
    ("tracker.protocol", 5), ("tracker.protocol", "carrier-pigeon"),
    ("tracker.url", 5),
    ("tracker.baudrate", "fast"), ("tracker.baudrate", 0), ("tracker.baudrate", 10**12),
    ("tracker.parity", "X"), ("tracker.parity", 5),
    ("tracker.timeout", "x"), ("tracker.timeout", 0), ("tracker.timeout", 1e12),
    ("tracker.position", "x"), ("tracker.position", [1, 2]), ("tracker.position", [1e308, 0.0, 0.0]),
    ("tracker.position", [1e6, 0.0, 0.3]),
    ("tracker.temperature", -300.0), ("tracker.temperature", 1000.0), ("tracker.temperature", "warm"),
    ("tracker.pressure", 0), ("tracker.pressure", 1e6),
    ("tracker.humidity", 500.0), ("tracker.humidity", -1.0),
    ("tracker.reflector", 5),
    ("tracker.measure_time", 0), ("tracker.measure_time", 1e12),
    ("tracker.warmup", -1), ("tracker.warmup", 1e12),
    ("tracker.bird_bath", "yes"),
    ("smr.offset", [10.0, 0.0, 0.0]), ("smr.offset", [1, 2]), ("smr.offset", ["a", "b", "c"]),
    ("smr.acceptance_angle", 0), ("smr.acceptance_angle", 90), ("smr.acceptance_angle", 180),
    ("smr.acceptance_angle", "wide"),
    ("keep_in.min", [2.0, 2.0, 2.0]), ("keep_in.min", "x"),
    ("keep_in.max", [1e308, 1e308, 1e308]), ("keep_in.max", [1, 2]),
    ("campaign.calibration_poses", 0), ("campaign.calibration_poses", 3),
    ("campaign.calibration_poses", 100_000_000), ("campaign.calibration_poses", "many"),
    ("campaign.validation_poses", 0), ("campaign.validation_poses", 100_000_000),
    ("campaign.validation_clusters", -1), ("campaign.validation_clusters", 3),
    ("campaign.validation_clusters", 40), ("campaign.validation_clusters", "x"),
    ("campaign.bootstrap_poses", 0), ("campaign.bootstrap_poses", 100_000_000),
    ("campaign.samples", 0), ("campaign.samples", 1_000_000_000),
    ("campaign.stability", 0), ("campaign.stability", -1), ("campaign.stability", 10.0),
    ("campaign.acceptance", 0), ("campaign.acceptance", -1), ("campaign.acceptance", 0.1),
    ("campaign.index", "O9"), ("campaign.index", 5),
    ("campaign.candidates", 0), ("campaign.candidates", 1_000_000_000),
    ("campaign.seed", -1), ("campaign.seed", "x"),
    ("campaign.selection", "fastest"), ("campaign.selection", 5),
    ("campaign.time_budget", -1), ("campaign.time_budget", 1e12), ("campaign.time_budget", "x"),
    ("campaign.time_budget", Raw("nan")),
    ("campaign.search_time", 0), ("campaign.search_time", -1), ("campaign.search_time", 1e6),
    ("campaign.search_time", "x"), ("campaign.search_time", Raw("nan")),
    ("campaign.plan_cache", 5), ("campaign.plan_cache", "   "),
    ("campaign.stop_early", "yes"), ("campaign.stop_early", 1),
    ("campaign.stop_margin", 0), ("campaign.stop_margin", -0.5), ("campaign.stop_margin", 1.5),
    ("campaign.stop_margin", "x"), ("campaign.stop_margin", Raw("nan")),
    ("timeouts.connect", 0), ("timeouts.connect", 1e12),
    ("timeouts.move", 0), ("timeouts.move", 1e12),
    ("timeouts.measure", 0), ("timeouts.measure", 1e12),
    ("timeouts.suspend", 0), ("timeouts.suspend", 1e12),
    ("timeouts.relock", 0), ("timeouts.relock", 1e12),
)

#: The config values of the issue, for the other commands that read a station config.
CONFIG_SUBSET: tuple[tuple[str, Any], ...] = (
    ("robot.speed", 1e9), ("robot.address", "not an address"), ("tracker.temperature", -300.0),
    ("tracker.humidity", 500.0), ("smr.offset", [10.0, 0.0, 0.0]), ("campaign.seed", -1),
    ("robot.joint_samples", 1_000_000_000), ("robot.type", "ur99"),
)


def _sim_config(robot: str, **sections: Mapping[str, Any]) -> Callable[[Path], str]:
    """A station config for the shared simulated UR5e station (address and tracker URL filled in when
    the case runs), claiming robot type `robot`; `sections` added (``verify``'s cube)."""
    def make(d: Path) -> str:
        doc = {s: dict(v) for s, v in {**BASE_CONFIG, **sections}.items()}
        doc["robot"]["type"] = robot
        doc["robot"]["address"] = "{sim_address}"
        doc["tracker"]["url"] = "{sim_tracker}"
        doc["keep_in"] = {"min": [-2.0, -2.0, 0.0], "max": [2.0, 2.0, 2.0]}
        return toml_text(doc)
    return make


CASES: list[Case] = _cases()


# --------------------------------------------------------------------------------------------------
# Running one case

class Tripwire(BaseException):
    """Something a bad input must never reach (a BaseException, so no `except Exception` hides it)."""


class CaseTimeout(BaseException):
    """The case ran longer than its time limit (bench runs; pytest uses pytest-timeout)."""


@dataclass
class SimStation:
    """The shared simulated UR5e station of the ``station=True`` cases."""

    address: str
    tracker_url: str
    process: Any

    def stop(self) -> None:
        self.process.stop()


def start_sim_station() -> SimStation:
    """A simulated UR5e station (robot + GeoCOM tracker) in its own process, for robot-type checks."""
    from mocks.station import start_station

    sim = start_station(robot="ur5e", speed=20.0, seed=2)
    return SimStation(sim.address, sim.info["services"][0]["tracker_url"], sim)


def _snapshot(root: Path) -> dict[str, str]:
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_fifo():
            out[str(p.relative_to(root))] = "fifo"
        elif p.is_file() and not p.is_symlink():
            out[str(p.relative_to(root))] = hashlib.sha256(p.read_bytes()).hexdigest()
        elif p.is_dir():
            out[str(p.relative_to(root)) + "/"] = "dir"
    return out


def _spellings(name: str) -> list[str]:
    """How an error may name `name` ("a|b": either): an option also by its words ("--half-angle":
    "half-angle", "half angle", "half_angle"); lower case."""
    out = []
    for alt in name.lower().split("|"):
        out.append(alt)
        if alt.startswith("--"):
            word = alt[2:]
            out += [word, word.replace("-", " "), word.replace("-", "_")]
    return out


def _substitute(text: str, values: Mapping[str, str]) -> str:
    return re.sub(r"\{(\w+)\}", lambda m: values.get(m.group(1), m.group(0)), text)


def _set_read_only(paths: Sequence[Path], on: bool) -> None:
    """Read-only media, as well as a test can: no write bits, and (as root, who ignores them) the
    immutable attribute, so not even a journal or a -wal file can be created beside the store."""
    for p in paths:
        if not p.exists():
            continue
        if on:
            p.chmod(0o555 if p.is_dir() else 0o444)
        if os.geteuid() == 0 and shutil.which("chattr"):
            subprocess.run(["chattr", "+i" if on else "-i", str(p)], check=False, capture_output=True)
        if not on:
            p.chmod(0o755 if p.is_dir() else 0o644)


@contextlib.contextmanager
def _tripwires(case: Case, station: SimStation | None) -> Iterator[list[Any]]:
    """Replace what starts or moves hardware (and the TUI app, and `hil sim`'s server) by tripwires."""
    import hil.station.devices as devices_mod
    import mocks.station as station_mod
    import mocks.ur.process as process_mod

    opened: list[Any] = []
    saved = [(devices_mod, "open_devices", devices_mod.open_devices),
             (devices_mod, "ask_controller", devices_mod.ask_controller),
             (station_mod, "start_station", station_mod.start_station),
             (process_mod, "serve", process_mod.serve)]
    real_open = devices_mod.open_devices

    def trip(what: str) -> Callable[..., Any]:
        def f(*args: Any, **kwargs: Any) -> Any:
            raise Tripwire(what)
        return f

    def open_without_motion(config: Any) -> Any:
        devices = real_open(config)
        opened.append(devices)
        for name in ("move_to", "follow"):
            setattr(devices.robot, name, trip(f"moved the arm ({name}) before refusing"))
        return devices

    if case.station:
        devices_mod.open_devices = open_without_motion
    else:
        devices_mod.open_devices = trip("connected to the robot/tracker before refusing")
        devices_mod.ask_controller = trip("asked the controller (connected to it) before refusing")
        station_mod.start_station = trip("started the simulated station before refusing")
    process_mod.serve = trip("started serving (hil sim) before refusing")
    tui_saved = None
    try:
        import hil.tui.app as app_mod

        tui_saved = app_mod.create_app
        app_mod.create_app = trip("opened the TUI app before refusing")
    except ImportError:
        app_mod = None
    try:
        yield opened
    finally:
        for module, attr, value in saved:
            setattr(module, attr, value)
        if app_mod is not None:
            app_mod.create_app = tui_saved
        for devices in opened:
            with contextlib.suppress(BaseException):
                devices.close()


@contextlib.contextmanager
def _environment(workdir: Path, env: Mapping[str, str]) -> Iterator[None]:
    """cwd = the case directory; the default database location inside it; `env` set."""
    saved_env = dict(os.environ)
    saved_cwd = os.getcwd()
    os.environ.pop("HIL_DB", None)
    os.environ["XDG_DATA_HOME"] = str(workdir / "xdg")
    os.environ.update(env)
    os.chdir(workdir)
    try:
        yield
    finally:
        os.chdir(saved_cwd)
        os.environ.clear()
        os.environ.update(saved_env)


@contextlib.contextmanager
def _memory_limit(extra: int = 6 << 30) -> Iterator[None]:
    """Cap the address space for the case (a huge count must fail fast, not swap a shared machine)."""
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    try:
        with open("/proc/self/status") as fh:
            vm = next(int(line.split()[1]) * 1024 for line in fh if line.startswith("VmSize:"))
    except (OSError, StopIteration):
        yield
        return
    limit = vm + extra
    if soft != resource.RLIM_INFINITY and soft <= limit:
        yield
        return
    resource.setrlimit(resource.RLIMIT_AS, (limit, hard))
    try:
        yield
    finally:
        resource.setrlimit(resource.RLIMIT_AS, (soft, hard))


@contextlib.contextmanager
def _alarm(seconds: float | None) -> Iterator[None]:
    if not seconds:
        yield
        return

    def expire(signum: int, frame: Any) -> None:
        raise CaseTimeout(f"no answer within {seconds:g} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


def prepare(case: Case, fixtures: Path, workdir: Path, station: SimStation | None = None) -> list[str]:
    """Fill `workdir` (fixtures, the case's files, an empty ``sub/``) and return the command line."""
    workdir.mkdir(parents=True, exist_ok=True)
    for name in FIXTURE_FILES:
        shutil.copy(fixtures / name, workdir / name)
    (workdir / "sub").mkdir(exist_ok=True)
    values = {"dir": str(workdir)}
    if station is not None:
        values.update(sim_address=station.address, sim_tracker=station.tracker_url)
    for name in case.fifos:
        os.mkfifo(workdir / name)
    for name, content in case.files.items():
        data = content(workdir) if callable(content) else content
        if isinstance(data, str):
            data = _substitute(data, values).encode()
        (workdir / name).parent.mkdir(parents=True, exist_ok=True)
        (workdir / name).write_bytes(data)
    return [_substitute(a, values) for a in case.argv]


class _FullStream(io.StringIO):
    """A stdout on a full device (``> /dev/full``): every write fails as the kernel fails it, and its
    descriptor is /dev/full's, as a shell's redirection makes it, so hil can tell it before writing."""

    def write(self, text: str) -> int:
        raise OSError(28, "No space left on device")

    def fileno(self) -> int:
        if not hasattr(self, "_fd"):
            self._fd = os.open("/dev/full", os.O_WRONLY)
        return self._fd

    def close(self) -> None:
        if hasattr(self, "_fd"):
            os.close(self._fd)
            del self._fd
        super().close()


def run_case(case: Case, fixtures: Path, workdir: Path, *, station: SimStation | None = None,
             timeout: float | None = None) -> Outcome:
    """Run `case` in `workdir` through `hil.cli.main` and judge it against the contract."""
    from hil.cli import main

    if case.station and station is None:
        raise ValueError(f"{case.name}: needs the simulated station")
    argv = prepare(case, fixtures, workdir, station)
    env = {k: _substitute(v, {"dir": str(workdir)}) for k, v in case.env.items()}
    read_only = [workdir / p for p in case.read_only]
    _set_read_only(read_only, True)
    before = _snapshot(workdir)
    out: Any = io.StringIO()
    err: Any = io.StringIO()
    if case.ascii:
        out = io.TextIOWrapper(io.BytesIO(), encoding="ascii", errors="strict")
        err = io.TextIOWrapper(io.BytesIO(), encoding="ascii", errors="strict")
    if case.stdout == "full":
        out = _FullStream()
    elif case.stdout == "closed":
        out = None
    problems: list[str] = []
    code: int | None = None
    start = time.monotonic()
    try:
        with (_environment(workdir, env), _tripwires(case, station), _memory_limit(),
              contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), _alarm(timeout)):
            code = main(argv)
    except Tripwire as exc:
        problems.append(str(exc))
    except CaseTimeout as exc:
        problems.append(f"hangs: {exc}")
    except SystemExit as exc:
        problems.append(f"SystemExit({exc.code}) escaped hil.cli.main")
    except MemoryError:
        problems.append("MemoryError escaped hil.cli.main")
    finally:
        seconds = time.monotonic() - start
        _set_read_only(read_only, False)
        if isinstance(out, _FullStream):
            out.close()
    after = _snapshot(workdir)
    if case.ascii:
        err.flush()
        text = err.buffer.getvalue().decode("ascii")
    else:
        text = err.getvalue()
    lines = [s for s in text.strip().splitlines() if s.strip()]
    if code is not None and code != case.expect:
        problems.insert(0, f"exit {code}, expected {case.expect}")
    if "Traceback" in text:
        problems.append("a traceback on stderr")
    if case.expect == 2 and code is not None:
        if len(lines) != 1:
            problems.append(f"{len(lines)} lines on stderr, expected one")
        line = text.strip().lower()
        for name in case.names:
            if not any(alt in line for alt in _spellings(name)):
                problems.append(f"the error does not name {name!r}")
    for path in sorted(set(before) | set(after)):
        if path not in after:
            problems.append(f"deleted {path}")
        elif path not in before:
            problems.append(f"created {path}")
        elif before[path] != after[path]:
            problems.append(f"modified {path}")
    return Outcome(case, code, text.strip(), problems, seconds)
