"""Issue 19, "outputs that destroy inputs": every file a subcommand writes is checked up front.

An output path that is one of the command's inputs, the campaign database (or its -wal file), another
output of the same command, an existing directory, or a path whose folder does not exist is bad input:
exit 2, one line on stderr naming the option, and nothing in the working folder changes (no byte of an
input, no file created). ``hil show last --db s.db --export-measurements s.db`` used to replace the whole
database with a CSV and exit 0; ``--out DIR`` ended in exit 70.

The table covers every (subcommand, output option) that `hil` registers: `test_the_table_covers_every_
output_option` fails when a command gains an output option without a row here.
"""

from __future__ import annotations

import argparse
import os
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest

from hil.calibration.model_file import MODEL_FORMAT, write_json
from hil.cli import build_parser, main
from hil.errors import InputError
from hil.files.outputs import check_output, check_output_dir

ROOT = Path(__file__).resolve().parents[3]
SQUARE = ROOT / "hil" / "moveb" / "examples" / "square.moveb"


# --- the working folder every case runs in: real inputs, a real store --------------------------------

def _store(path: Path) -> None:
    """A campaign database with one accepted campaign: measurements and a model to export."""
    from hil.arm.geometry import Geometry
    from hil.campaign.events import ModelIdentified, PointMeasured, RunFinished, RunStarted
    from hil.station.config import default_config
    from hil.store import RobotIdentity, Store

    model = {"format": MODEL_FORMAT, **Geometry.nominal("ur5e").to_dict(),
             "parameters": [{"name": "p", "value": 0.0, "std": 1e-6}] * 27,
             "fit": {"rms": 18e-6, "max": 45e-6, "iterations": 6, "rejected": []},
             "input": {"file": "campaign", "sha256": "0" * 64}}
    with Store.open(path) as s:
        cid = s.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "2023550002"), now=1.7e9)
        s.save_plan(cid, [(i, "calibration", [0.1 * i] * 6) for i in range(3)])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="cell", poses=3))
        for i in range(3):
            s.record_event(PointMeasured(campaign=cid, index=i, role="calibration", q=[0.1 * i] * 6,
                                         p=[1.0, 2.0, i], p_spread=[0] * 3, samples=5))
        s.record_event(ModelIdentified(campaign=cid, rms=18e-6, max=45e-6, iterations=6, rejected=[],
                                       model=model))
        s.record_event(RunFinished(campaign=cid, status="accepted"))


@pytest.fixture(scope="module")
def base(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Inputs as the commands would really read them: a synthetic truth and its measurements, a model
    identified from them, a MOVEB program, a result file, a store, an empty folder."""
    root = tmp_path_factory.mktemp("inputs")
    assert main(["synth", "--robot", "ur5e", "--poses", "30", "--validation", "20", "--seed", "4",
                 "--out-dir", str(root)]) == 0
    assert main(["identify", "--robot", "ur5e", "--measurements", str(root / "measurements.csv"),
                 "--out", str(root / "model.json")]) == 0
    shutil.copy(SQUARE, root / "square.moveb")
    write_json(root / "result.json", {"format": "hil-result/1"})
    _store(root / "s.db")
    (root / "folder").mkdir()
    return root


@pytest.fixture
def work(base: Path, tmp_path: Path) -> Path:
    """A fresh copy of the inputs for one case (so one case's damage cannot hide another's)."""
    return Path(shutil.copytree(base, tmp_path / "w"))


def _snapshot(root: Path) -> dict[str, bytes | None]:
    """Every path under `root` with its bytes (None for a folder): what must not change."""
    return {str(p.relative_to(root)): (None if p.is_dir() else p.read_bytes()) for p in root.rglob("*")}


# --- the table: (subcommand, option, kind) -> command line and what the one line must say -------------

Case = Callable[[Path], list[str]]
SIM = ["--sim", "--ideal", "--speed", "20", "--seed", "2"]


def _cases() -> list[tuple[str, str, str, Case, str]]:
    """(command, option, kind, argv of the working folder w, words the error line must hold)."""
    w: Callable[[Path, str], str] = lambda d, name: str(d / name)  # noqa: E731
    missing = "nowhere/x.out"  # a folder that does not exist
    ident = lambda d: ["identify", "--robot", "ur5e", "--measurements", w(d, "measurements.csv"),  # noqa: E731
                       "--validation", w(d, "validation.csv"), "--out"]
    fk = lambda d: ["fk", "--model", w(d, "model.json"), "--joints", w(d, "validation.csv"), "--out"]  # noqa: E731
    export = lambda d: ["export", "--model", w(d, "model.json"), "--format", "json", "--out"]  # noqa: E731
    comp = lambda d: ["compensate", "--model", w(d, "model.json"), "--controller", w(d, "truth.json"),  # noqa: E731
                      w(d, "validation.csv"), "--out"]
    report = lambda d: ["report", "--result", w(d, "result.json"), "--out"]  # noqa: E731
    select = lambda d: ["select", "--robot", "ur5e", "--count", "12", "--candidates", "1000",  # noqa: E731
                        "--no-bound", "--quiet", "--out"]
    synth = lambda d: ["synth", "--truth", w(d, "truth.json"), "--poses", "5", "--out-dir"]  # noqa: E731
    show = lambda d, opt: ["show", "last", "--db", w(d, "s.db"), opt]  # noqa: E731
    cal = lambda d: ["calibrate", *SIM, "--truth", w(d, "truth.json"), "--db", w(d, "s.db")]  # noqa: E731
    ver = lambda d: ["verify", *SIM, "--truth", w(d, "truth.json"), "--model", w(d, "model.json"),  # noqa: E731
                     "--db", w(d, "s.db")]
    plan = lambda d: ["moveb", "plan", w(d, "square.moveb"), "--out"]  # noqa: E731
    mrun = lambda d: ["moveb", "run", w(d, "square.moveb"), *SIM, "--truth", w(d, "truth.json"),  # noqa: E731
                      "--model", w(d, "model.json")]
    tui = lambda d: ["tui", "--sim", "--db", w(d, "s.db"), "--out-dir"]  # noqa: E731
    robot = lambda d: ["robot", "2023550002", "--db", w(d, "s.db"), "--export-model"]  # noqa: E731
    fleet = lambda d: ["fleet-report", "--db", w(d, "s.db"), "--out"]  # noqa: E731
    return [
        ("robot", "--export-model", "store", lambda d: [*robot(d), w(d, "s.db")], "is the store (--db"),
        ("robot", "--export-model", "store", lambda d: [*robot(d), w(d, "s.db-wal")], "store's wal file"),
        ("robot", "--export-model", "directory", lambda d: [*robot(d), w(d, "folder")], "is a directory"),
        ("robot", "--export-model", "missing parent", lambda d: [*robot(d), w(d, missing)],
         "does not exist"),
        ("fleet-report", "--out", "store", lambda d: [*fleet(d), w(d, "s.db")], "is the store (--db"),
        ("fleet-report", "--out", "directory", lambda d: [*fleet(d), w(d, "folder")], "is a directory"),
        ("fleet-report", "--out", "missing parent", lambda d: [*fleet(d), w(d, missing)], "does not exist"),
        ("identify", "--out", "input", lambda d: [*ident(d), w(d, "measurements.csv")],
         "input --measurements"),
        ("identify", "--out", "input", lambda d: [*ident(d), w(d, "validation.csv")], "input --validation"),
        ("identify", "--out", "directory", lambda d: [*ident(d), w(d, "folder")], "is a directory"),
        ("identify", "--out", "missing parent", lambda d: [*ident(d), w(d, missing)], "does not exist"),
        ("fk", "--out", "input", lambda d: [*fk(d), w(d, "model.json")], "input --model"),
        ("fk", "--out", "input", lambda d: [*fk(d), w(d, "validation.csv")], "input --joints"),
        ("fk", "--out", "directory", lambda d: [*fk(d), w(d, "folder")], "is a directory"),
        ("fk", "--out", "missing parent", lambda d: [*fk(d), w(d, missing)], "does not exist"),
        ("export", "--out", "input", lambda d: [*export(d), w(d, "model.json")], "input --model"),
        ("export", "--out", "directory", lambda d: [*export(d), w(d, "folder")], "is a directory"),
        ("export", "--out", "missing parent", lambda d: [*export(d), w(d, missing)], "does not exist"),
        ("compensate", "--out", "input", lambda d: [*comp(d), w(d, "model.json")], "input --model"),
        ("compensate", "--out", "input", lambda d: [*comp(d), w(d, "truth.json")], "input --controller"),
        ("compensate", "--out", "input", lambda d: [*comp(d), w(d, "validation.csv")], "input INPUT"),
        ("compensate", "--out", "directory", lambda d: [*comp(d), w(d, "folder")], "is a directory"),
        ("compensate", "--out", "missing parent", lambda d: [*comp(d), w(d, missing)], "does not exist"),
        ("report", "--out", "input", lambda d: [*report(d), w(d, "result.json")], "input --result"),
        ("report", "--out", "directory", lambda d: [*report(d), w(d, "folder")], "is a directory"),
        ("report", "--out", "missing parent", lambda d: [*report(d), w(d, missing)], "does not exist"),
        ("select", "--out", "directory", lambda d: [*select(d), w(d, "folder")], "is a directory"),
        ("select", "--out", "missing parent", lambda d: [*select(d), w(d, missing)], "does not exist"),
        ("synth", "--out-dir", "input", lambda d: [*synth(d), str(d)], "input --truth"),
        ("synth", "--out-dir", "a file", lambda d: [*synth(d), w(d, "model.json")], "not a directory"),
        ("synth", "--out-dir", "missing parent", lambda d: [*synth(d), w(d, "nowhere/out")],
         "does not exist"),
        ("show", "--export-model", "store", lambda d: [*show(d, "--export-model"), w(d, "s.db")],
         "is the store (--db"),
        ("show", "--export-model", "store", lambda d: [*show(d, "--export-model"), w(d, "s.db-wal")],
         "store's wal file"),
        ("show", "--export-model", "directory", lambda d: [*show(d, "--export-model"), w(d, "folder")],
         "is a directory"),
        ("show", "--export-model", "missing parent",
         lambda d: [*show(d, "--export-model"), w(d, missing)], "does not exist"),
        ("show", "--export-measurements", "store",
         lambda d: [*show(d, "--export-measurements"), w(d, "s.db")], "is the store (--db"),
        ("show", "--export-measurements", "store",
         lambda d: [*show(d, "--export-measurements"), w(d, "s.db-journal")], "store's journal file"),
        ("show", "--export-measurements", "directory",
         lambda d: [*show(d, "--export-measurements"), w(d, "folder")], "is a directory"),
        ("show", "--export-measurements", "missing parent",
         lambda d: [*show(d, "--export-measurements"), w(d, missing)], "does not exist"),
        ("show", "--export-measurements", "other output",
         lambda d: [*show(d, "--export-model"), w(d, "m.csv"), "--export-measurements", w(d, "m.csv")],
         "also the output --export-model"),
        ("calibrate", "--out", "store", lambda d: [*cal(d), "--out", w(d, "s.db")], "is the store (--db"),
        ("calibrate", "--out", "input", lambda d: [*cal(d), "--out", w(d, "truth.json")], "input --truth"),
        ("calibrate", "--out", "directory", lambda d: [*cal(d), "--out", w(d, "folder")], "is a directory"),
        ("calibrate", "--out", "missing parent", lambda d: [*cal(d), "--out", w(d, missing)],
         "does not exist"),
        ("calibrate", "--report", "store", lambda d: [*cal(d), "--report", w(d, "s.db-wal")],
         "store's wal file"),
        ("calibrate", "--report", "input", lambda d: [*cal(d), "--report", w(d, "truth.json")],
         "input --truth"),
        ("calibrate", "--report", "directory", lambda d: [*cal(d), "--report", w(d, "folder")],
         "is a directory"),
        ("calibrate", "--report", "missing parent", lambda d: [*cal(d), "--report", w(d, missing)],
         "does not exist"),
        ("calibrate", "--report", "other output",
         lambda d: [*cal(d), "--out", w(d, "r.json"), "--report", w(d, "r.json")], "also the output --out"),
        ("verify", "--out", "store", lambda d: [*ver(d), "--out", w(d, "s.db")], "is the store (--db"),
        ("verify", "--out", "input", lambda d: [*ver(d), "--out", w(d, "model.json")], "input --model"),
        ("verify", "--out", "input", lambda d: [*ver(d), "--out", w(d, "truth.json")], "input --truth"),
        ("verify", "--out", "directory", lambda d: [*ver(d), "--out", w(d, "folder")], "is a directory"),
        ("verify", "--out", "missing parent", lambda d: [*ver(d), "--out", w(d, missing)], "does not exist"),
        ("verify", "--report", "store", lambda d: [*ver(d), "--report", w(d, "s.db-wal")],
         "store's wal file"),
        ("verify", "--report", "input", lambda d: [*ver(d), "--report", w(d, "model.json")], "input --model"),
        ("verify", "--report", "directory", lambda d: [*ver(d), "--report", w(d, "folder")],
         "is a directory"),
        ("verify", "--report", "missing parent", lambda d: [*ver(d), "--report", w(d, missing)],
         "does not exist"),
        ("verify", "--report", "other output",
         lambda d: [*ver(d), "--out", w(d, "r.json"), "--report", w(d, "r.json")], "also the output --out"),
        ("moveb plan", "--out", "input", lambda d: [*plan(d), w(d, "square.moveb")], "input PROGRAM"),
        ("moveb plan", "--out", "directory", lambda d: [*plan(d), w(d, "folder")], "is a directory"),
        ("moveb plan", "--out", "missing parent", lambda d: [*plan(d), w(d, missing)], "does not exist"),
        ("moveb run", "--out", "input", lambda d: [*mrun(d), "--out", w(d, "model.json")], "input --model"),
        ("moveb run", "--out", "input", lambda d: [*mrun(d), "--out", w(d, "square.moveb")],
         "input PROGRAM"),
        ("moveb run", "--out", "directory", lambda d: [*mrun(d), "--out", w(d, "folder")], "is a directory"),
        ("moveb run", "--out", "missing parent", lambda d: [*mrun(d), "--out", w(d, missing)],
         "does not exist"),
        ("moveb run", "--plot", "input", lambda d: [*mrun(d), "--plot", w(d, "truth.json")], "input --truth"),
        ("moveb run", "--plot", "directory", lambda d: [*mrun(d), "--plot", w(d, "folder")],
         "is a directory"),
        ("moveb run", "--plot", "missing parent", lambda d: [*mrun(d), "--plot", w(d, missing)],
         "does not exist"),
        ("moveb run", "--plot", "other output",
         lambda d: [*mrun(d), "--out", w(d, "r.out"), "--plot", w(d, "r.out")], "also the output --out"),
        ("tui", "--out-dir", "a file", lambda d: [*tui(d), w(d, "model.json")], "not a directory"),
        ("tui", "--out-dir", "missing parent", lambda d: [*tui(d), w(d, "nowhere/out")], "does not exist"),
    ]


CASES = _cases()


@pytest.fixture
def no_app(monkeypatch: pytest.MonkeyPatch) -> list[object]:
    """`hil tui` without the terminal app: a stand-in that records that it was started and exits 0."""
    import hil.tui.app

    started: list[object] = []

    class _App:
        def run(self) -> int:
            return 0

    def create_app(options: object) -> _App:
        started.append(options)
        return _App()

    monkeypatch.setattr(hil.tui.app, "create_app", create_app)
    return started


@pytest.mark.parametrize(("command", "option", "kind", "argv", "says"), CASES,
                         ids=[f"{c}-{o}-{k}-{i}" for i, (c, o, k, _, _) in enumerate(CASES)])
def test_a_bad_output_path_is_refused_up_front(command: str, option: str, kind: str, argv: Case, says: str,
                                               work: Path, no_app: list[object],
                                               capsys: pytest.CaptureFixture[str]) -> None:
    before = _snapshot(work)
    code = main(argv(work))
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"hil: error: {option}: "), err  # the option the user must change
    assert says in lines[0], err
    assert _snapshot(work) == before  # no input byte changed, no file or folder created
    assert not no_app  # the terminal app never started


def test_the_table_covers_every_output_option() -> None:
    """Each output option of every subcommand has rows for what applies to it; commands without one
    (validate, sim, history) write nothing."""
    written = {"out", "out_dir", "report", "plot", "export_model", "export_measurements"}

    def outputs(parser: argparse.ArgumentParser, prefix: str) -> set[tuple[str, str]]:
        found = set()
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, child in action.choices.items():
                    found |= outputs(child, f"{prefix} {name}".strip())
            elif action.dest in written:
                found.add((prefix, max(action.option_strings, key=len)))
        return found

    registered = outputs(build_parser(), "")
    assert registered == {(c, o) for c, o, _, _, _ in CASES}
    kinds = {(c, o): {k for c2, o2, k, _, _ in CASES if (c2, o2) == (c, o)} for c, o in registered}
    for (command, option), seen in kinds.items():
        assert {"directory", "missing parent"} <= seen or {"a file", "missing parent"} <= seen, (command,
                                                                                                 option)


@pytest.mark.parametrize("command", ["show", "identify", "fk"])
def test_the_store_named_by_the_environment_is_protected_too(command: str, work: Path,
                                                             monkeypatch: pytest.MonkeyPatch,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    """Commands that never open the store still must not write over the one ``$HIL_DB`` names."""
    monkeypatch.setenv("HIL_DB", str(work / "s.db"))
    argv, option = {
        "show": (["show", "last", "--export-measurements"], "--export-measurements"),
        "identify": (["identify", "--robot", "ur5e", "--measurements", str(work / "measurements.csv"),
                      "--out"], "--out"),
        "fk": (["fk", "--model", str(work / "model.json"), "--joints", str(work / "validation.csv"),
                "--out"], "--out")}[command]
    before = _snapshot(work)
    assert main([*argv, str(work / "s.db")]) == 2
    err = capsys.readouterr().err
    assert f"{option}: " in err and "is the store ($HIL_DB" in err, err
    assert _snapshot(work) == before


def test_the_default_store_is_protected(work: Path, monkeypatch: pytest.MonkeyPatch,
                                        capsys: pytest.CaptureFixture[str]) -> None:
    """No --db, no $HIL_DB: the user's default database (under $XDG_DATA_HOME) is the store."""
    monkeypatch.delenv("HIL_DB", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(work))
    (work / "hil").mkdir()
    shutil.copy(work / "s.db", work / "hil" / "hil.db")
    before = _snapshot(work)
    assert main(["export", "--model", str(work / "model.json"), "--format", "json", "--out",
                 str(work / "hil" / "hil.db")]) == 2
    assert "is the store (the campaign database" in capsys.readouterr().err
    assert _snapshot(work) == before


def test_a_store_not_created_yet_is_protected(work: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``calibrate --db new.db --out new.db``: the store does not exist yet, the path is still its."""
    new = work / "new.db"
    assert main(["calibrate", *SIM, "--db", str(new), "--out", str(work / "." / "new.db")]) == 2
    assert "is the store (--db" in capsys.readouterr().err
    assert not new.exists()


@pytest.mark.parametrize("link", ["symlink", "hard link", "dotted path"])
def test_an_input_under_another_name_is_still_the_input(link: str, work: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    source = work / "measurements.csv"
    alias = work / "alias.csv"
    if link == "symlink":
        alias.symlink_to(source)
    elif link == "hard link":
        os.link(source, alias)
    else:
        alias = work / "folder" / ".." / "measurements.csv"
    before = _snapshot(work)
    assert main(["identify", "--robot", "ur5e", "--measurements", str(source), "--out", str(alias)]) == 2
    assert "--out:" in capsys.readouterr().err
    assert _snapshot(work) == before


def test_a_good_output_path_is_accepted(work: Path) -> None:
    """The guard returns the path it accepts and lets a missing directory of outputs be created."""
    assert check_output(work / "new.json", field="--out", inputs={"--model": work / "model.json"},
                        store=work / "s.db") == work / "new.json"
    assert check_output(work / "model.json", field="--out") == work / "model.json"  # overwriting: fine
    # a store on a database server is no file an output could replace
    assert check_output(work / "x.json", field="--out", store="postgresql://127.0.0.1/hil") == work / "x.json"
    assert check_output_dir(work / "fresh", field="--out-dir", names=("a.json",)) == work / "fresh"
    with pytest.raises(InputError, match=r"^--out: "):
        check_output("", field="--out")
