"""How to call every armctl command quickly, and every numeric option it takes: one table for
the property tests (tests/test_config_values.py in-process, tests/test_cli_properties.py in
fresh processes).

A new command fails ``test_every_command_has_a_quick_invocation`` until it has a row here, and
then inherits every property those files check; a new numeric option is found through click's
own command objects.
"""

from __future__ import annotations

import click

from armctl.ui.cli import main

VIRTUAL_SIM = "sim://?clock=virtual"

# The arguments after the command's name; the option under test is appended.  Each ends quickly
# with or without an accepted value ("{script}" is a small valid script).
QUICK_INVOCATIONS = {
    "bench": ["--size", "test", "--scenario", "tiny", "--jobs", "1"],
    "compile": ["{script}"],
    "config": [],
    "completion": ["bash"],
    "decode": ["{script}"],
    "estimate": ["{script}"],
    "home": ["--port", VIRTUAL_SIM],
    "jog": ["--port", VIRTUAL_SIM],  # refuses a virtual clock (or a non-terminal) at once
    "lint": ["{script}"],
    "move": ["z=200", "--port", VIRTUAL_SIM],
    "plot": ["{script}", "-o", "{script}.svg", "--view", "xy"],
    "ports": [],
    "probe": ["--port", VIRTUAL_SIM, "--no-motion", "--json"],
    "run": ["{script}", "--no-live", "--port", VIRTUAL_SIM],
    "serve": ["--listen", "no-port-here", "--arm", f"a={VIRTUAL_SIM}"],  # a bad --listen: exit 2 at once
    "sim": ["--pty"],  # with --tcp as well: "choose one", at once
    "status": ["--once", "--port", VIRTUAL_SIM],
}


def all_commands(group: click.Group = main, path: tuple[str, ...] = ()):
    """(path of names, command) for every command, sub-groups included, sorted."""
    for name, command in sorted(group.commands.items()):
        if isinstance(command, click.Group):
            yield from all_commands(command, (*path, name))
        else:
            yield (*path, name), command


def quick_args(path: tuple[str, ...], script) -> list[str]:
    return [*path, *(part.format(script=script) for part in QUICK_INVOCATIONS[path[0]])]


def is_numeric(param: click.Parameter) -> bool:
    return isinstance(param, click.Option) and not param.is_flag and isinstance(param.type, click.types._NumberParamTypeBase)


def numeric_options() -> list[tuple[tuple[str, ...], click.Option]]:
    """(command path, option) for every option whose type is a number, read from click."""
    return [(path, param) for path, command in all_commands() for param in command.params if is_numeric(param)]
