"""The layers of the package, as the tree shows them (README, "The package"): a job's data goes
down — the user interfaces (armctl/ui, server, plot, jog) over the host edge (armctl/host: ports,
clocks, threads, files, the Python API) over the pure core (armctl/core with the language,
armctl/script and armctl/lint) — and never climbs back.  These read the source, imports inside
functions included: a lazy import that climbs is still a layer that needs the one above it."""

from __future__ import annotations

import ast
from pathlib import Path

from test_structure import PACKAGE, _imports, _modules

# what the pure core may never import: a clock, a thread, a port, a terminal, a process
IO_MODULES = {"time", "threading", "serial", "click", "rich", "queue", "socket", "select", "signal", "asyncio",
              "subprocess", "concurrent", "termios", "tty"}
USER_INTERFACES = ("armctl.ui", "armctl.server", "armctl.plot", "armctl.jog")


def _edges(prefix: str) -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(name, path, modules) for name, path in modules.items()
            if name == prefix or name.startswith(prefix + ".")}


def _under(name: str, prefixes) -> bool:
    return any(name == p or name.startswith(p + ".") for p in prefixes)


def test_the_core_imports_only_the_core_and_the_language():
    allowed = ("armctl.core", "armctl.errors", "armctl.script", "armctl.lint.engine", "armctl.lint.rules",
               "armctl.lint.registry", "armctl.lint.tracker", "armctl.lint.scan", "armctl.lint")
    climbing = {f"{name} -> {target}" for name, targets in _edges("armctl.core").items()
                for target in targets if not _under(target, allowed)}
    assert climbing == set()


def test_the_core_imports_no_clock_thread_port_or_terminal():
    found = set()
    for path in (PACKAGE / "core").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                roots = {alias.name.split(".")[0] for alias in node.names}
            elif isinstance(node, ast.ImportFrom) and not node.level:
                roots = {(node.module or "").split(".")[0]}
            else:
                continue
            found.update(f"{path.relative_to(PACKAGE.parent)}: {root}" for root in roots & IO_MODULES)
    assert found == set()


def test_the_host_edge_never_calls_up_into_a_user_interface():
    climbing = {f"{name} -> {target}" for name, targets in _edges("armctl.host").items()
                for target in targets if _under(target, USER_INTERFACES)}
    assert climbing == set()


def test_the_simulator_never_calls_up_into_a_user_interface_or_the_host_s_job():
    climbing = {f"{name} -> {target}" for name, targets in _edges("armctl.sim").items()
                for target in targets if _under(target, USER_INTERFACES + ("armctl.host.api", "armctl.host.runner",
                                                                            "armctl.host.jobflow", "armctl.host.driver"))}
    assert climbing == set()


def test_the_top_of_the_package_shows_the_layers():
    """At the top: the layers, the feature packages, errors (every layer's) and the two public
    entries, ``armctl`` itself (``Arm``) and ``armctl.aio`` (``AsyncArm``)."""
    top = {p.stem if p.suffix == ".py" else p.name for p in PACKAGE.iterdir()
           if p.name != "__pycache__" and (p.suffix == ".py" or (p / "__init__.py").exists())}
    assert top <= {"__init__", "__main__", "errors", "aio", "core", "host", "sim", "ui", "script", "lint", "probe", "jog",
                   "bench", "plot", "server", "data"}
