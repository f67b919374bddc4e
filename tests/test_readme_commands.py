"""The README's commands, as a newcomer copies them (its rule: "every command the README shows
works as written or says what to install").

Cheap and deterministic checks only; the commands themselves were run by hand in a fresh clone
(the audit of wt-readme).  Every ``armctl …`` the README shows — a command line of a code block
or an inline span — names a subcommand armctl has and only options that subcommand takes,
read from click's own command objects and from ``armctl SUBCOMMAND --help`` of the installed
command in a fresh process; the second command at the top is the one .ci/run runs; every
script and benchmark a command names is in the repository.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import click
import pytest

from armctl.ui.cli import main

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
ARMCTL = Path(sys.executable).with_name("armctl")

# Inline spans that name armctl but are no command: a row of bench's table (a strategy).
NOT_COMMANDS = {"armctl no probe"}
_FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.M | re.S)
# a command line of a code block: optionally after "$ ", "- run: ", "eval "$(", "… | "
_BLOCK_COMMAND = re.compile(r"(?:^|\$\(|\|\s*|^\$\s+|^-\s+run:\s+)((?:\.venv/bin/)?armctl\s[^#\n)]*)")


def readme_commands() -> list[tuple[int, str]]:
    """(line, command) for every armctl command the README shows, ``.venv/bin/`` dropped."""
    text = README.read_text(encoding="utf-8")
    found: list[tuple[int, str]] = []
    for fence in _FENCE.finditer(text):
        if fence.group(1) not in ("", "sh", "yaml"):
            continue
        first = text.count("\n", 0, fence.start(2)) + 1
        lines = fence.group(2).splitlines()
        transcript = any(line.startswith("$ ") for line in lines)  # then the other lines are output
        for offset, line in enumerate(lines):
            if transcript and not line.startswith("$ "):
                continue
            found += [(first + offset, match.group(1)) for match in _BLOCK_COMMAND.finditer(line.strip())]
    prose = _FENCE.sub(lambda fence: "\n" * fence.group(0).count("\n"), text)
    for number, line in enumerate(prose.splitlines(), 1):
        for span in re.findall(r"`([^`]+)`", line):
            if re.match(r"(?:\.venv/bin/)?armctl\s", span) and span not in NOT_COMMANDS:
                found.append((number, span))
    return [(number, command.removeprefix(".venv/bin/").strip()) for number, command in found]


def subcommand_and_options(command: str) -> tuple[str | None, list[str]]:
    """The subcommand (None for a placeholder such as ``armctl -v …``) and every option named
    after it (``[--mode joint|linear]`` gives ``--mode``, ``--pty/--tcp`` both)."""
    words = [word.strip("[]") for word in command.replace("\\|", "|").split()[1:]]
    while words and words[0] in ("-v", "-q", "--verbose", "--quiet"):
        words = words[1:]
    if not words or not re.fullmatch(r"[a-z]+", words[0]):
        return None, []
    options = [part.split("=")[0] for word in words[1:] if word.startswith("-") and word != "-"
               for part in word.split("/")]
    return words[0], options


def option_names(command: click.Command) -> set[str]:
    names = {"-h", "--help"}
    for param in command.params:
        names.update(param.opts, param.secondary_opts)
    return names


def table_options() -> set[tuple[str, str]]:
    """Options the README names beside their command rather than in one span: the rows of
    "What it does" (``| `armctl probe` | … `--list`, `--forget` |``), the rows of lint's
    option table, and the commands **JSON:** says take ``--json``."""
    text = README.read_text(encoding="utf-8")
    named: set[tuple[str, str]] = set()
    in_lint_table = False
    for line in text.splitlines():
        row = re.match(r"\| `armctl (\w+)", line)
        in_lint_table = line.startswith("| option | what it does |") or (in_lint_table and line.startswith("|"))
        name = row.group(1) if row else "lint" if in_lint_table else None
        for span in re.findall(r"`(-[^`]+)`", line) if name else ():
            named.update((name, part.split()[0]) for part in span.split("/"))
    json_list = re.search(r"takes `--json` \(([^)]*)\)", text)
    named.update((name, "--json") for name in re.findall(r"`(\w+)`", json_list.group(1)))
    return named


COMMANDS = readme_commands()
NAMED = sorted({(name, option) for _line, command in COMMANDS
                for name, options in [subcommand_and_options(command)] if name for option in options}
               | table_options())


def test_the_readme_shows_commands_of_every_kind():
    names = {subcommand_and_options(command)[0] for _line, command in COMMANDS}
    assert {"run", "move", "home", "lint", "plot", "probe", "serve", "completion", "bench"} <= names, names
    assert len(NAMED) >= 20, NAMED


@pytest.mark.parametrize("line, command", COMMANDS, ids=[f"line{line}" for line, _command in COMMANDS])
def test_every_readme_command_names_a_subcommand_and_options_it_has(line, command):
    name, options = subcommand_and_options(command)
    if name is None:
        return
    assert name in main.commands, f"README line {line}: `{command}`: armctl has no command {name!r}"
    unknown = [option for option in options if option not in option_names(main.commands[name])]
    assert not unknown, f"README line {line}: `{command}`: armctl {name} has no option {unknown}"


@pytest.mark.parametrize("name, option", NAMED, ids=[f"{name} {option}" for name, option in NAMED])
def test_every_option_named_beside_its_command_is_one_it_has(name, option):
    assert name in main.commands and option in option_names(main.commands[name]), (name, option)


@pytest.mark.timeout(120)
def test_every_option_the_readme_names_is_in_the_installed_commands_help():
    """The same, through the installed command in fresh processes: one ``--help`` per subcommand."""
    by_command: dict[str, list[str]] = {}
    for name, option in NAMED:
        by_command.setdefault(name, []).append(option)
    for name, options in sorted(by_command.items()):
        done = subprocess.run([str(ARMCTL), name, "--help"], capture_output=True, text=True, timeout=30)
        assert done.returncode == 0, (name, done.stderr)
        listed = set(re.findall(r"(?<![\w-])(--?[A-Za-z][\w-]*)", done.stdout))
        assert not set(options) - listed, f"armctl {name} --help does not list {sorted(set(options) - listed)}"


def test_the_readme_test_command_is_the_one_ci_runs():
    readme = README.read_text(encoding="utf-8")
    top = readme[readme.index("```sh"):readme.index("```", readme.index("```sh") + 3)]
    test_command = next(line for line in top.splitlines() if "pytest" in line).removeprefix("python3 -m venv .venv && ")
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
    runs = ci[ci.index("# README, second command:") + 1].replace("--quiet ", "")
    assert runs == test_command


def test_every_script_and_benchmark_a_readme_command_names_exists():
    text = _FENCE.sub(lambda fence: "" if fence.group(1) == "text" else fence.group(0),  # not output
                      README.read_text(encoding="utf-8"))
    named = set(re.findall(r"\b((?:scripts|benchmarks)/\w+\.(?:txt|py))\b", text))
    assert "scripts/pick_and_place.txt" in named and "benchmarks/virtual_run.py" in named
    assert not [path for path in sorted(named) if not (ROOT / path).is_file()]
