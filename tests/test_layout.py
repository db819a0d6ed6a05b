"""The layout's rules, read from the code's own imports (those inside functions and TYPE_CHECKING too).

* `selector` and `drivers` know nothing of `hil`;
* inside `hil`, a package imports only packages below it (cli and tui on top, the jobs below them;
  campaign above calibration above arm);
* the front-ends meet only in the jobs layer: the terminal app imports nothing of the command line,
  and no command module imports another (what they share lives in `hil.cli.support`);
* the station is taken in one place: only `hil.jobs.station` locks the arm's address and opens the
  devices (`hil.store.address_lock`, `hil.station.devices.open_devices`);
* no module imports, directly or through others, a module that imports it back (no import circles).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOP = ("hil", "selector", "drivers", "mocks")

#: hil's packages from the bottom up; a package may import only those before it (and itself).
HIL_LAYERS: tuple[str, ...] = (
    "errors", "files", "arm", "calibration", "compensation", "station", "campaign", "store", "verify",
    "report", "moveb", "jobs", "tui", "cli",
)


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for top in TOP for p in (ROOT / top).rglob("*.py")}


def _imports(name: str, path: Path, known: set[str]) -> set[str]:
    """Project modules `name` imports; `from pkg import mod` imports both pkg (its face) and pkg.mod."""
    is_package = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if is_package else name.split(".")[:-1]
                base = base[: len(base) - node.level + 1]
                module = ".".join([*base, node.module] if node.module else base)
            else:
                module = node.module or ""
            out.add(module)
            out.update(f"{module}.{alias.name}" for alias in node.names)
    return {m for m in out if m in known and m != name}


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    known = set(modules)
    return {name: _imports(name, path, known) for name, path in modules.items()}


GRAPH = _graph()


def _hil_package(module: str) -> str | None:
    parts = module.split(".")
    if parts[0] != "hil" or len(parts) < 2:
        return None
    return parts[1] if parts[1] in HIL_LAYERS else None


def test_the_graph_is_read() -> None:
    assert "hil.campaign.engine" in GRAPH and "hil.campaign.events" in GRAPH["hil.campaign.engine"]


@pytest.mark.parametrize("top", ["selector", "drivers"])
def test_selector_and_drivers_know_nothing_of_hil(top: str) -> None:
    wrong = sorted(f"{m} -> {d}" for m, deps in GRAPH.items() if m.split(".")[0] == top
                   for d in deps if d.split(".")[0] in ("hil", "mocks"))
    assert not wrong, "\n".join(wrong)


def test_hil_packages_import_only_downwards() -> None:
    rank = {name: i for i, name in enumerate(HIL_LAYERS)}
    wrong = []
    for module, deps in GRAPH.items():
        here = _hil_package(module)
        if here is None:
            continue
        for dep in deps:
            there = _hil_package(dep)
            if there is not None and rank[there] > rank[here]:
                wrong.append(f"{module} ({here}) -> {dep} ({there})")
    assert not wrong, "\n".join(sorted(wrong))


def test_every_hil_module_lives_in_a_package_of_the_layout() -> None:
    loose = sorted(m for m in GRAPH if m.startswith("hil.") and m.split(".")[1] not in HIL_LAYERS
                   and m != "hil.__main__")
    assert not loose, loose


def test_no_import_circles() -> None:
    # Tarjan's strongly connected components; a component of more than one module is a circle
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    assert not circles, "\n".join(" <-> ".join(c) for c in circles)


def test_the_terminal_app_imports_nothing_of_the_command_line() -> None:
    wrong = sorted(f"{m} -> {d}" for m, deps in GRAPH.items() if m.startswith("hil.tui")
                   for d in deps if d == "hil.cli" or d.startswith("hil.cli."))
    assert not wrong, "\n".join(wrong)


def _command_module(module: str) -> bool:
    parts = module.split(".")
    return len(parts) == 3 and parts[:2] == ["hil", "cli"] and parts[2] != "support"


def test_no_command_module_imports_another() -> None:
    wrong = sorted(f"{m} -> {d}" for m, deps in GRAPH.items() if _command_module(m)
                   for d in deps if _command_module(d) and d != m)
    assert not wrong, "\n".join(wrong)


def _names_used(path: Path) -> set[str]:
    """Every name a module imports or reads as an attribute (``devices.open_devices`` included)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.Attribute):
            out.add(node.attr)
    return out


@pytest.mark.parametrize("name", ["address_lock", "open_devices"])
def test_the_station_is_taken_in_one_place(name: str) -> None:
    """The arm's lock and its devices are taken by `hil.jobs.station` alone: a guard added there guards
    every job (the store defines the lock, `hil.station.devices` the devices; neither takes them)."""
    modules = _modules()
    takers = sorted(m for m, path in modules.items() if m.startswith("hil.") and name in _names_used(path)
                    and m not in ("hil.store", "hil.store.leases", "hil.station.devices"))
    assert takers == ["hil.jobs.station"], takers
