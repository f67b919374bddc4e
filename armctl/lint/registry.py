"""The table of every code lint can report, and which of them a run selects.

Strategy: one table, ``RULES``: the language's own codes (``armctl.script.RULES``, E0xx —
whatever the parser and compiler reject) followed by lint's codes (L1xx geometry, L2xx speeds,
L3xx PWM, L4xx parameters, loops and empty scripts, L5xx the state a script ends in).  A lint
rule is a small function registered with ``@rule(code, severity, name, rationale, on=...)``;
``on`` says what it looks at: protocol command classes (it sees each compiled statement of
those kinds), ``END`` (it sees the tracker once the script is over) or ``SOURCE`` (rules fed by
the line scanner rather than by statements).  Codes are stable: CI configs and inline
``; armctl: ignore[CODE]`` comments refer to them.

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
    severity: str
    name: str  # short kebab-case name, for --statistics and docs
    rationale: str  # one line: why the rule exists


# code → Rule(severity, rationale), language codes first; every code lint can report.
RULES: dict[str, Rule] = dict(LANGUAGE_RULES)
# code → LintRule for lint's own codes.
LINT_RULES: dict[str, LintRule] = {}
# command class (or END) → [(code, function)], in registration order.
CHECKS: dict[object, list[tuple[str, Callable]]] = {}


def rule(code: str, severity: str, name: str, rationale: str, on: Iterable | str = ()) -> Callable:
    """Register a rule under ``code``; with ``on`` also register the decorated function as its check."""
    if code in RULES:
        raise ValueError(f"rule code {code} is registered twice")
    if severity not in (ERROR, WARNING):
        raise ValueError(f"{code}: severity must be {ERROR!r} or {WARNING!r}")
    RULES[code] = Rule(severity, rationale)
    LINT_RULES[code] = LintRule(code, severity, name, rationale)
    targets = [on] if isinstance(on, str) else list(on)

    def register(function: Callable) -> Callable:
        for target in targets:
            if target != SOURCE:
                CHECKS.setdefault(target, []).append((code, function))
        function.code = code
        return function

    return register


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
