"""Issue 22, deliverable 4 (the CLI half): whatever bytes a user's files and options hold, every
command ends 0, 1 or 2 with a message — never a traceback, never a hang.

Strategy: Hypothesis writes the files and options a user controls — an arm profile
(``--profile``), an armctl.toml (in the working directory), the options of a ``sim://`` URL
(``--port``, with ``profile=`` naming a generated file too), scripts with huge repeat counts,
lint rule codes and prefixes in ``--select``/``--ignore`` and in ``[lint]`` — each either as raw
bytes or as TOML built from the real schemas (``armctl.host.profile.PROFILE_SCHEMA``, ``CONFIG_SCHEMA``, the
jog settings, ``sim://``'s option table), so most examples get past the TOML parser to the checks
behind it, with values from the edges: whole numbers past 64 bits, floats near the float32 and
float64 limits, NaN, inf, strings with NUL or a BOM, lists nested deeper than any setting.  The
bulk runs in-process (click's CliRunner: ``check_in_process`` of tests/test_cli_properties.py,
which fails on any exception that escapes a command); a few examples of each kind go through
the installed command in a fresh process, each under a timeout.  Found by it, before its fixes:
the reproducers of tests/test_inputs_toml.py (TypeError, OverflowError, ValueError and
RecursionError tracebacks from a profile or armctl.toml).
"""

from __future__ import annotations

import json
import math
import random
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from test_cli_properties import EDGE_NUMBER_TEXTS, check_fresh, check_in_process, codes_from_the_package, number_texts

SETTINGS = settings(max_examples=60, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
JOB = "G1 X250 Y0 Z150 A180 B0 C0 S1000 F6000\nG4 P10\nG1 Z140\n"
VIRTUAL = "sim://?clock=virtual"


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty directory holding job.txt, with no armctl.toml above it and no ARMCTL_* set."""
    from armctl.host.profile import find_config

    monkeypatch.chdir(tmp_path)
    for name in [k for k in __import__("os").environ if k.startswith("ARMCTL_")]:
        monkeypatch.delenv(name)
    assert find_config(tmp_path)[0] is None, "an armctl.toml above the temporary directory"
    (tmp_path / "job.txt").write_text(JOB)
    return tmp_path


# --- TOML built from the schemas, with values from the edges ------------------------------------


def _schema_keys() -> dict[str, list[str]]:
    """Section → keys: the profile's schema, armctl.toml's top level, [jog] and [lint]."""
    from dataclasses import fields

    from armctl.jog.settings import JogSettings
    from armctl.lint.command import CONFIG_KEYS
    from armctl.host.profile import PROFILE_SCHEMA, CONFIG_SCHEMA

    sections = {name: list(rule) for name, rule in PROFILE_SCHEMA.items() if isinstance(rule, dict)}
    sections["jog"] = [f.name for f in fields(JogSettings)] + ["keys"]
    sections["lint"] = list(CONFIG_KEYS)
    sections[""] = [name for name, rule in PROFILE_SCHEMA.items() if not isinstance(rule, dict)] + list(CONFIG_SCHEMA)
    return sections


SECTIONS = _schema_keys()
SPECIAL_FLOATS = ("inf", "-inf", "nan", "+nan", "1e309", "-1e309", "3.4028235e38", "3.4028236e38", "1.4e-45", "5e-324",
                  "1.7976931348623157e308", "0.0", "-0.0")


def _float_token(x: float) -> str:
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    text = repr(x)
    return text if any(c in text for c in ".en") else text + ".0"


scalar_tokens = st.one_of(
    st.integers(min_value=-(2**63), max_value=2**63 - 1).map(str),
    st.integers(min_value=-(10**420), max_value=10**420).map(str),  # past TOML's 64 bits
    st.sampled_from(["9" * 400, "-" + "9" * 400, "9" * 400, "9" * 5000]),  # the reproducers' sizes
    st.floats().map(_float_token),
    st.floats(width=32).map(_float_token),
    st.sampled_from(SPECIAL_FLOATS),
    st.booleans().map(lambda b: "true" if b else "false"),
    st.text(st.characters(exclude_categories=("Cs",), exclude_characters="\x7f"), max_size=12).map(
        lambda s: json.dumps(s, ensure_ascii=False)),  # a TOML basic string: json's escapes of control characters are TOML's
    st.sampled_from(['"a\\u0000b"', '"\\ufeff"', '""', '" "', '"open"', '"closed"', '"queued"', '"robot"',
                     '"sim://"', '"sim://["', '"/dev/zero"', '"."', '"profile.toml"', '"L203"', '"E"', '"ALL"']),
)


def _nested(depth: int, inner: str) -> str:
    return "[" * depth + inner + "]" * depth


structured_tokens = st.recursive(
    scalar_tokens,
    lambda inner: st.one_of(
        st.lists(inner, max_size=6).map(lambda items: "[" + ", ".join(items) + "]"),
        st.lists(st.tuples(st.sampled_from([k for keys in SECTIONS.values() for k in keys]), inner), max_size=3)
        .map(lambda pairs: "{" + ", ".join(f"{json.dumps(k)} = {v}" for k, v in dict(pairs).items()) + "}"),
    ),
    max_leaves=12,
)
# lists nested around a value, one value in five: 31 deep is allowed, 33 is not, 2000 is past tomllib's recursion
value_tokens = st.one_of(*[structured_tokens] * 4, st.builds(_nested, st.sampled_from([2, 7, 31, 33, 40, 2000]), scalar_tokens))

key_names = st.one_of(st.sampled_from(sorted({k for keys in SECTIONS.values() for k in keys})),
                      st.text(alphabet="abcdefghijklmnopqrstuvwxyz_0123456789-", min_size=1, max_size=10))


@st.composite
def toml_documents(draw, sections: tuple[str, ...]) -> bytes:
    """A TOML document (mostly valid TOML): top-level keys, then tables from ``sections`` (a
    "profile." prefix: armctl.toml's [profile] table), each key from its schema or made up."""
    # each key and table once, and no top-level key named like a table: most documents are valid TOML
    tables = draw(st.lists(st.sampled_from(sections), max_size=4, unique=True))
    taken = {table.split(".", 1)[0] for table in tables}
    top = draw(st.lists(st.sampled_from(SECTIONS[""]) | key_names, max_size=3, unique=True))
    lines = [f"{key} = {draw(value_tokens)}" for key in top if key not in taken]
    for section in tables:
        lines.append(f"[{section}]")
        base = section.rsplit(".", 1)[-1]
        keys = draw(st.lists(st.sampled_from(SECTIONS.get(base) or ["x"]) | key_names, max_size=4, unique=True))
        lines += [f"{key} = {draw(value_tokens)}" for key in keys]
    text = "\n".join(lines) + "\n"
    prefix = draw(st.sampled_from([b""] * 6 + [b"\xef\xbb\xbf", b"\x00", b"\xff"]))
    return prefix + text.encode("utf-8", "surrogatepass")


PROFILE_SECTIONS = tuple(name for name in SECTIONS if name and name not in ("jog",))
CONFIG_SECTIONS = ("connector", "lint", "jog", "profile", *(f"profile.{s}" for s in PROFILE_SECTIONS if s != "lint"))
file_bytes = {
    "profile": st.one_of(toml_documents(PROFILE_SECTIONS), st.binary(max_size=300)),
    "config": st.one_of(toml_documents(CONFIG_SECTIONS), st.binary(max_size=300)),
}

PROFILE_COMMANDS = (["estimate", "--profile", "profile.toml", "job.txt"], ["lint", "--profile", "profile.toml", "job.txt"],
                    ["run", "--dry-run", "--profile", "profile.toml", "job.txt"],
                    ["status", "--once", "--port", VIRTUAL + "&profile=profile.toml"])
CONFIG_COMMANDS = (["config"], ["config", "--json"], ["estimate", "job.txt"], ["lint", "job.txt"],
                   ["run", "--dry-run", "job.txt"], ["status", "--once", "--port", VIRTUAL])


@SETTINGS
@given(data=file_bytes["profile"], command=st.sampled_from(PROFILE_COMMANDS))
def test_any_bytes_as_a_profile(workdir, data, command):
    (workdir / "profile.toml").write_bytes(data)
    check_in_process(command)


@SETTINGS
@given(data=file_bytes["config"], command=st.sampled_from(CONFIG_COMMANDS))
def test_any_bytes_as_armctl_toml(workdir, data, command):
    (workdir / "armctl.toml").write_bytes(data)
    (workdir / "profile.toml").write_text("[connector]\nfifo_frames = 150\n")  # what a `profile = "profile.toml"` finds
    check_in_process(command)


# --- sim:// options ------------------------------------------------------------------------------


def _option_names() -> list[str]:
    from armctl.sim.protocol_sim import OPTION_NAMES

    return list(OPTION_NAMES)


sim_values = st.one_of(number_texts, st.sampled_from(EDGE_NUMBER_TEXTS), st.sampled_from(
    ["", "virtual", "wall", "queued", "arrival", "robot", "worktable", "profile.toml", "/dev/zero", "%00", "a%00b",
     "[", "]", "%", "%zz", "&", "=", "\u00e9", "\x7f"]), st.text(max_size=8))
sim_queries = st.lists(st.tuples(st.sampled_from(_option_names()) | st.text(max_size=6), sim_values), max_size=5).map(
    lambda pairs: "&".join(f"{k}={v}" for k, v in pairs))
sim_urls = st.one_of(
    sim_queries.map(lambda q: f"{VIRTUAL}&{q}" if q else VIRTUAL),
    st.text(max_size=30).map(lambda tail: "sim://" + tail),  # anything after the scheme: [, #, @, :, /, …
    st.sampled_from(["sim://[", "sim://[x]?clock=virtual", "sim://?clock=virtual#frag", "sim:///x", "sim://?&&&",
                     "sim://?clock=virtual&clock=virtual", "sim://?clock=virtual&speed=2", "sim:?clock=virtual"]),
)


@SETTINGS
@given(url=sim_urls, profile=file_bytes["profile"])
def test_any_sim_options(workdir, url, profile):
    (workdir / "profile.toml").write_bytes(profile)
    if "clock=virtual" not in url:  # a wall-clock simulator would be waited for in real time
        url = url + ("&" if "?" in url else "?") + "clock=virtual"
    check_in_process(["status", "--once", "--timeout", "0.5", "--port", url])


# --- scripts with huge repeat counts ---------------------------------------------------------------


# Counts a test can afford to compile when they are valid (up to 10,000 passes), and counts at and
# past the 2,000,000-line bound, NaN, inf, huge, negative and fractional ones: refused at once.
count_texts = st.one_of(st.integers(0, 10_000).map(str), st.integers(2_000_000, 10**30).map(str),
                        st.sampled_from(EDGE_NUMBER_TEXTS), st.sampled_from(["1e9", "2e6", "-1", "0.5", "[1/0]", "[0/0]",
                                                                             "#<n>", "[#<n> * 1e300]"]))


@st.composite
def repeat_scripts(draw):
    depth = draw(st.integers(1, 4))
    counts = [draw(count_texts) for _ in range(depth)]
    closed = draw(st.integers(0, depth))  # how many of the blocks are closed (the outer ones may stay open)
    body = draw(st.sampled_from(["G1 Z140", "G1 Z150\nG1 Z140", "G91\nG1 Z0.001", "#<n> = [#<n> + 1]", "M3", ""]))
    opens = "".join(f"O{k} repeat [{c}]\n" for k, c in enumerate(counts))
    closes = "".join(f"O{k} endrepeat\n" for k in reversed(range(depth - closed, depth)))
    return "#<n> = 3\n" + JOB + opens + body + "\n" + closes


@SETTINGS
@given(script=repeat_scripts(), command=st.sampled_from([["compile"], ["lint"], ["estimate"], ["run", "--dry-run"]]))
def test_huge_repeat_counts(workdir, script, command):
    (workdir / "loop.txt").write_text(script)
    check_in_process([*command, "loop.txt"])


# --- lint rule codes --------------------------------------------------------------------------------


def _codes() -> list[str]:
    codes = codes_from_the_package()
    return codes + sorted({code[:n] for code in codes for n in (1, 2, 3)}) + ["ALL", "all", "e0", "Q999", "", " ", ",,"]


code_lists = st.lists(st.sampled_from(_codes()) | st.text(max_size=5), max_size=6)


@SETTINGS
@given(select=code_lists, ignore=code_lists, table=st.booleans())
def test_any_rule_codes_in_select_and_ignore(workdir, select, ignore, table):
    args = ["lint", "job.txt"]
    if table:  # the same codes in armctl.toml's [lint]
        (workdir / "armctl.toml").write_text(f"[lint]\nselect = {json.dumps(select)}\nignore = {json.dumps(ignore)}\n")
    else:
        args += [x for code in select for x in ("--select", code)] + [x for code in ignore for x in ("--ignore", code)]
    check_in_process(args)


# --- a few of each through the installed command -----------------------------------------------------


def _seeded_bytes(seed: int, size: int = 200) -> bytes:
    return random.Random(seed).randbytes(size)


FRESH_FILES = {
    "profile: random bytes": ("profile.toml", _seeded_bytes(1), ["estimate", "--profile", "profile.toml", "job.txt"]),
    "profile: list channel": ("profile.toml", b"[pwm]\nchannels = [[1], 2]\n", ["lint", "--profile", "profile.toml", "job.txt"]),
    "profile: 64 bits + 1": ("profile.toml", b"[connector]\nfifo_frames = 9223372036854775808\n",
                             ["run", "--dry-run", "--profile", "profile.toml", "job.txt"]),
    "armctl.toml: random bytes": ("armctl.toml", _seeded_bytes(2), ["config"]),
    "armctl.toml: deep [jog]": ("armctl.toml", b"[jog]\nstep_mm = " + b"[" * 40 + b"1" + b"]" * 40 + b"\n", ["config", "--json"]),
    "armctl.toml: float32 edge": ("armctl.toml", b"[connector]\nspeed_factor = 3.4028235e38\n", ["estimate", "job.txt"]),
    "sim profile: random bytes": ("profile.toml", _seeded_bytes(3), ["status", "--once", "--port", VIRTUAL + "&profile=profile.toml"]),
}


@pytest.mark.parametrize("name, data, command", FRESH_FILES.values(), ids=FRESH_FILES.keys())
def test_hostile_files_through_the_installed_command(tmp_path, name, data, command):
    (tmp_path / "job.txt").write_text(JOB)
    (tmp_path / name).write_bytes(data)
    code, _out, err = check_fresh(command, tmp_path)
    assert code == 2, err
    assert re.search(r"(profile|armctl)\.toml", err), err  # the one line names the file


@pytest.mark.parametrize("url", ["sim://[", VIRTUAL + "&seed=" + "9" * 5000, VIRTUAL + "&profile=a%00b",
                                 VIRTUAL + "&fifo_frames=nan&baud=inf", "sim://?clock=virtual&%zz=1"])
def test_hostile_sim_urls_through_the_installed_command(tmp_path, url):
    code, _out, err = check_fresh(["status", "--once", "--port", url], tmp_path)
    assert code == 2, err


@pytest.mark.parametrize("script", [JOB + "O1 repeat [999990]\nG1 Z140\n", JOB + "O1 repeat [1e400]\nG1 Z140\nO1 endrepeat\n",
                                    JOB + "O1 repeat [nan]\nO2 repeat [2000001]\nM3\nO2 endrepeat\n"])
def test_hostile_repeats_through_the_installed_command(tmp_path, script):
    (tmp_path / "loop.txt").write_text(script)
    for command in (["compile"], ["lint"]):
        code, _out, _err = check_fresh([*command, "loop.txt"], tmp_path)
        assert code == 1
