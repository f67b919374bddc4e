"""The table of every code lint can report, and which of them a run selects.

Strategy: one table, ``RULES``: the language's own codes (``armctl.script.RULES``, E0xx —
whatever the parser and compiler reject) followed by lint's codes (L1xx geometry, L2xx speeds,
L3xx PWM, L4xx parameters, loops and empty scripts, L5xx the state a script ends in).  Lint's
codes are a static declaration here (``LINT_RULES``): the table is complete as soon as this
module is imported, whoever imports it first.  A check is a small function in rules.py
attached to its declared code with ``@check(code, on=...)``; ``on`` says what it looks at:
protocol command classes (it sees each compiled statement of those kinds) or ``END`` (it sees
the tracker once the script is over); codes declared ``SOURCE`` are fed by the line scanner
rather than by statements.  Codes are stable: CI configs and inline ``; armctl: ignore[CODE]``
comments refer to them.

``Selection`` answers "is this code reported?" from ``--select`` / ``--ignore`` lists, where
each entry is a code or a prefix of codes (``L2`` = every speed rule, ``E`` = every language
code), like ruff.  Pure: no I/O.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable, NamedTuple

from ..script import ERROR, RULES as LANGUAGE_RULES, WARNING, Rule

END = "end"  # a rule that looks at the tracker after the last statement
SOURCE = "source"  # a rule fed by the line scanner (armctl/lint/scan.py), not by statements


class LintRule(NamedTuple):
    code: str
    severity: str  # for a finding on measured numbers; one resting on illustrative ones is a warning
    name: str  # short kebab-case name, for --statistics and docs
    rationale: str  # one line: why the rule exists
    fed_by: str = "check"  # "check": a function in rules.py registers with @check; SOURCE: the scanner


# Lint's own codes, declared here and nowhere else, so that every caller — --select/--ignore,
# armctl.toml's [lint] table, --list-rules, the formatters — sees the whole table whatever it
# imported first.  rules.py attaches a check to each "check" code (tests/test_lint_registry.py
# fails for a code without a check and @check refuses a check without a code).
LINT_RULES: dict[str, LintRule] = {rule.code: rule for rule in (
    LintRule("L101", ERROR, "arc-degenerate",
             "three arc points that coincide or lie on one line define no circle"),
    LintRule("L102", ERROR, "arc-radius",
             "an R that disagrees with the circle through the arc's three points makes the path ambiguous"),
    LintRule("L103", ERROR, "outside-workspace",
             "a target outside the profile's workspace box or reach, or with no joint solution inside the limits,"
             " stops or crashes the arm"),
    LintRule("L104", ERROR, "joint-limit",
             "a joint angle outside the profile's limits drives the joint into its end stop"),
    LintRule("L201", ERROR, "speed-above-max",
             "a speed above the profile's maximum is more than the arm is rated for (and its ETA is wrong)"),
    LintRule("L202", ERROR, "joint-speed-in-mm-min",
             "a G6 speed far above the joint maximum was almost always meant as mm/min; G6 F is deg/s"),
    LintRule("L203", WARNING, "cartesian-speed-in-deg-s",
             "a Cartesian speed below 1 mm/s reads like deg/s; G1/G22x/G300/G301 F is mm/min"),
    LintRule("L204", ERROR, "accel-above-max",
             "an acceleration above the profile's maximum is more than the arm is rated for"),
    LintRule("L301", ERROR, "pwm-channel-unwired",
             "a PWM value sent to a channel the profile does not wire moves nothing (the gripper is on PWM 1)"),
    LintRule("L302", ERROR, "pwm-outside-profile-range",
             "a PWM pulse outside the profile's range drives the servo past its end stop"),
    LintRule("L401", WARNING, "unused-parameter",
             "a parameter assigned but never read is usually a typo in its name or a leftover", SOURCE),
    LintRule("L402", WARNING, "repeat-never-runs",
             "a repeat count of 0 skips its block; a count must be a positive whole number to do anything", SOURCE),
    LintRule("L403", WARNING, "empty-script",
             "a script without a single statement sends nothing to the arm", SOURCE),
    LintRule("L501", ERROR, "end-gripper",
             "the profile's lint.end_gripper says how every job must leave the gripper (e.g. open, part released)"),
    LintRule("L502", ERROR, "end-paused",
             "the profile's lint.end_paused says whether a job may end paused (PAUSE toggles)"),
)}

# code → Rule(severity, rationale), language codes first; every code lint can report.
RULES: dict[str, Rule] = {**LANGUAGE_RULES, **{code: Rule(r.severity, r.rationale) for code, r in LINT_RULES.items()}}
# command class (or END) → [(code, function)], in registration order; filled by rules.py.
CHECKS: dict[object, list[tuple[str, Callable]]] = {}


def check(code: str, on: Iterable | str) -> Callable:
    """Attach the decorated function to the declared ``code`` as its check on ``on`` (command
    classes, or END).  A code that is not declared in LINT_RULES, is fed by the scanner, or
    already has a check is a programming error, raised at import."""
    declared = LINT_RULES.get(code)
    if declared is None or declared.fed_by != "check":
        raise ValueError(f"@check({code!r}): not a code declared for a check in LINT_RULES")
    if code in checked_codes():
        raise ValueError(f"@check({code!r}): the code already has a check")
    targets = [on] if isinstance(on, str) else list(on)
    if not targets:
        raise ValueError(f"@check({code!r}): say what the check looks at (on=...)")

    def register(function: Callable) -> Callable:
        for target in targets:
            CHECKS.setdefault(target, []).append((code, function))
        function.code = code
        return function

    return register


def checked_codes() -> set[str]:
    """The codes that have a check registered (all "check" codes once rules.py is imported)."""
    return {code for entries in CHECKS.values() for code, _ in entries}


def rule_name(code: str) -> str:
    """A short name for any code: lint's own name, or the language rationale's first words."""
    if code in LINT_RULES:
        return LINT_RULES[code].name
    summary = RULES[code].summary
    return summary.split(":", 1)[0].strip() if ":" in summary else summary


def severity_of(code: str) -> str:
    return RULES[code].severity


class UnknownCode(ValueError):
    """A --select / --ignore / inline-ignore entry that matches no code."""


@dataclass(frozen=True)
class Selection:
    """Which codes are reported: those matching ``select`` (default: all) and not ``ignore``."""

    select: tuple[str, ...] = ()
    ignore: tuple[str, ...] = ()

    @classmethod
    def of(cls, select: Iterable[str] = (), ignore: Iterable[str] = ()) -> "Selection":
        """Normalised (upper case, stripped) and checked: each entry must match some code."""
        return cls(tuple(check_prefixes(select)), tuple(check_prefixes(ignore)))

    def __contains__(self, code: str) -> bool:
        if self.select and not matches(code, self.select):
            return False
        return not matches(code, self.ignore)

    def codes(self) -> list[str]:
        return [code for code in RULES if code in self]


def matches(code: str, prefixes: Iterable[str]) -> bool:
    return any(code.startswith(prefix) for prefix in prefixes)


def check_prefixes(entries: Iterable[str]) -> list[str]:
    """Entries upper-cased; raises UnknownCode for one that matches no code."""
    out = []
    for entry in entries:
        prefix = entry.strip().upper()
        if not prefix:
            continue
        if prefix != "ALL" and not any(code.startswith(prefix) for code in RULES):
            raise UnknownCode(f"unknown rule code or prefix {entry.strip()!r} (armctl lint --list-rules shows them)")
        out.append("" if prefix == "ALL" else prefix)
    return out
