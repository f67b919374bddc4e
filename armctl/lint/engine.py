"""Lint one script: compile it as a stream, run the rules, keep what the user asked to see.

Strategy: one pass.  The line scanner (armctl/lint/scan.py) watches the lines on their way to
the compiler; every statement the compiler yields is shown to the rules registered for its
command class (armctl/lint/rules.py), then the arm tracker advances; END rules and the
scanner's findings follow; the compiler's own diagnostics are taken as they are.  Each finding
passes the selection (--select/--ignore) and the line's inline ``; armctl: ignore[…]``
comment and is counted per code; lint keeps up to ``max_diagnostics`` of its own findings
per file and the compiler as many of its own — so memory stays flat for a script of any
length and any number of findings; ``FileReport.hidden`` says how many were not kept.

A finding's severity is its code's, except that an error resting on a number the packaged
profile only illustrates (a rule's ``rests_on``, armctl/host/profile.py's provenance) is a warning
that names those numbers: a finding is only as true as the numbers it rests on, and a warning
never blocks ``run``.  So ``FileReport`` counts errors and warnings per finding, not per code.

A statement inside a repeat block is checked on every pass (a G91 loop may leave the
workspace on its third pass only) but each (line, code) is reported for one pass only: the
first that finds it.  Passes stop once one repeats the one before it exactly (same commands,
same modal state after): the rest could only say the same again.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field
from typing import Iterable, Optional

from ..script import DEFAULT_MAX_DIAGNOSTICS, ERROR, WARNING, Diagnostic, SourceSpan, compile_lines
from . import rules as _rules  # noqa: F401 - registers the rules
from .registry import CHECKS, END, Selection, matches, severity_of
from .scan import LineScanner, ignored_codes
from .tracker import ArmTracker


@dataclass
class FileReport:
    """What lint found in one script."""

    file: str
    diagnostics: list[Diagnostic] = field(default_factory=list)  # kept, sorted by position
    counts: Counter = field(default_factory=Counter)  # code → findings (kept or not)
    severities: Counter = field(default_factory=Counter)  # (code, severity) → findings (kept or not)
    hidden: int = 0  # findings counted but not kept (over max_diagnostics)
    uncounted_errors: int = 0  # compiler errors beyond its cap: not kept, code unknown
    lines: int = 0

    @property
    def errors(self) -> int:
        counted = sum(n for (_, severity), n in self.severities.items() if severity == ERROR)
        return counted + self.uncounted_errors

    @property
    def warnings(self) -> int:
        return sum(n for (_, severity), n in self.severities.items() if severity == WARNING)


class _Collector:
    """Filters, de-duplicates, counts and keeps findings for one report."""

    def __init__(self, report: FileReport, selection: Selection, max_diagnostics: int, profile=None) -> None:
        self.report, self.selection, self.max, self.profile = report, selection, max_diagnostics, profile
        self._passes: dict = {}  # (line, code) → the repeat pass that reported it first

    def add(self, code: str, where, message: str, hint: Optional[str], loop: tuple = (), rests_on: tuple = ()) -> None:
        """``where``: a SourceSpan, or a rules.WordAt resolved to one only if the finding is kept;
        ``rests_on``: the profile keys the finding depends on (see the module docstring)."""
        if code not in self.selection or _silenced(code, where.text):
            return
        if loop:  # report a loop line's code on one pass only (every finding of that pass)
            first = self._passes.setdefault((where.line, code), loop)
            if first != loop:
                return
            if any(loop):
                message += f" (repeat pass {'/'.join(str(i + 1) for i in loop)})"
        severity = severity_of(code)
        if severity == ERROR and rests_on and self.profile is not None:
            unmeasured = self.profile.illustrative(rests_on)
            if unmeasured:
                severity = WARNING
                message += (f" ({', '.join(unmeasured)}: illustrative numbers from the built-in profile;"
                            " give your arm's profile with --profile)")
        self.report.counts[code] += 1
        self.report.severities[code, severity] += 1
        if len(self.report.diagnostics) < self.max:
            span = where if type(where) is SourceSpan else where.resolve()
            self.report.diagnostics.append(Diagnostic(span, code, severity, message, hint))
        else:
            self.report.hidden += 1

    def add_diagnostic(self, diagnostic: Diagnostic) -> None:
        """A compiler diagnostic: always kept (the compiler keeps at most max_diagnostics itself),
        so that lint's own findings never crowd out the errors that stop a script compiling.
        A language *error* (E…) is reported whatever the selection or an inline ignore says, as
        ruff reports syntax errors: compile and run refuse the script anyway, so a lint that
        passed it would be untrue."""
        selected = diagnostic.code in self.selection and not _silenced(diagnostic.code, diagnostic.span.text)
        if selected or diagnostic.is_error:
            self.report.counts[diagnostic.code] += 1
            self.report.severities[diagnostic.code, diagnostic.severity] += 1
            self.report.diagnostics.append(diagnostic)


def _silenced(code: str, text: str) -> bool:
    codes = ignored_codes(text)
    return codes is not None and (not codes or matches(code, codes))


class _MotionClock:
    """The job's motion time as ``run`` and ``estimate`` judge it (E012, ``motion_time_overrun``),
    from the profile's fixed pose 0.  A repeat pass that repeated itself stands for the passes
    lint skips (``Compilation.skipped_passes``): it starts and ends where they would, so each of
    them takes its time again.  A nested block's skipped passes inside a pass that is itself
    skipped are counted once, so the sum may fall short of the job's, never exceed it: a job
    lint finds too long surely is (``run`` and ``estimate`` judge the whole expansion).
    Reported once.  Timed with ``Planner.feed_s``: the same seconds as ``feed``, without a
    segment and an end pose per line (issue 13)."""

    def __init__(self, profile, compilation) -> None:
        from ..core.estimate import motion_time_overrun
        from ..core.motion import MotionModel, Planner
        from ..script.source import MAX_JOB_MOTION_S

        self._overrun = motion_time_overrun  # imported once, not once a statement
        self._bound_s = MAX_JOB_MOTION_S
        model = MotionModel(profile)
        self._planner = Planner(model, model.initial_pose())
        self._feed_s = self._planner.feed_s
        self._skipped = compilation.skipped_passes  # the compiler appends to this very list
        self._skips_seen = 0
        self._motion_s = 0.0
        self._last = None
        self._reported = False

    def feed(self, statement):
        """Count ``statement`` (and the passes skipped before it); E012 once the sum passes the bound."""
        if self._reported:
            return None
        if self._skips_seen < len(self._skipped):
            self._count_skipped()
        self._motion_s = motion_s = self._motion_s + self._feed_s(statement.command)
        self._last = statement
        if motion_s <= self._bound_s:
            return None  # motion_time_overrun's own first test, without the call
        return self._judge(statement)

    def finish(self):
        """After the last statement: passes skipped at the very end count too (E012 at that statement)."""
        if self._reported or self._last is None:
            return None
        self._count_skipped()
        return self._judge(self._last)

    def _count_skipped(self) -> None:
        skipped = self._skipped
        while self._skips_seen < len(skipped):
            commands, passes = skipped[self._skips_seen]
            self._skips_seen += 1
            self._motion_s += passes * self._pass_s(commands)

    def _judge(self, statement):
        overrun = self._overrun(statement, self._motion_s)
        self._reported = overrun is not None
        return overrun

    def _pass_s(self, commands) -> float:
        """One more run of a pass that ends where it starts: planned from here, the planner left as it was."""
        from ..core.motion import Planner

        planner = Planner(self._planner.model, self._planner.pose)
        return sum(planner.feed_s(command) for command in commands)


def lint_lines(lines: Iterable[str], file: str, profile, selection: Optional[Selection] = None, *,
               max_diagnostics: int = DEFAULT_MAX_DIAGNOSTICS, initial=None) -> FileReport:
    """Lint a script given as lines (an iterator is read once, lazily) against ``profile``;
    ``selection`` defaults to every code.  ``initial`` (a ``script.InitialState``, e.g. from the
    arm's report): what the compiler knows before line 1; default nothing, as for a file."""
    selection = Selection() if selection is None else selection
    report = FileReport(file)
    collector = _Collector(report, selection, max_diagnostics, profile)
    checks = {kind: [(code, check) for code, check in entries if code in selection]
              for kind, entries in CHECKS.items()}
    compilation = None
    scanner = LineScanner(file, lambda: compilation.state.parameters, collector.add)
    # skip_repeats: a repeat pass that repeats the last one exactly has nothing new to say, so
    # lint's cost follows the text, not the repeat counts (see armctl/script/compiler.py)
    compilation = compile_lines(scanner.watch(lines), file, initial, max_diagnostics=max_diagnostics, skip_repeats=True)
    arm = ArmTracker(profile)
    clock = _MotionClock(profile, compilation)
    checks_of, apply, feed = checks.get, arm.apply, clock.feed  # once, not once a statement
    for statement in compilation:
        for code, check in checks_of(type(statement.command), ()):
            for span, message, hint, *rests_on in check(statement, arm):
                collector.add(code, span, message, hint, statement.loop, *rests_on)
        apply(statement)
        overrun = feed(statement)
        if overrun is not None:
            collector.add_diagnostic(overrun)
    overrun = clock.finish()
    if overrun is not None:
        collector.add_diagnostic(overrun)
    for code, check in checks.get(END, ()):
        for span, message, hint, *rests_on in check(arm):
            collector.add(code, span, message, hint, (), *rests_on)
    for code, span, message, hint in scanner.unused_parameters():
        collector.add(code, span, message, hint)
    if arm.statements == 0 and compilation.error_count == 0 and not scanner.not_text:
        what = "the file is empty" if scanner.lines == 0 else "the script has no statements"
        collector.add("L403", SourceSpan(file, 1, 1, 1, scanner.first_line), f"{what}: it sends nothing to the arm",
                      "armctl lint checks motion scripts; is this the file you meant?")
    for diagnostic in compilation.diagnostics:
        collector.add_diagnostic(diagnostic)
    reported = {d.span.line for d in compilation.diagnostics if d.code == "E011"}
    for code, span, message, hint in scanner.not_text:
        if span.line not in reported:
            collector.add(code, span, message, hint)
    # errors the compiler counted beyond its own cap: their codes are unknown, so they count as errors
    report.uncounted_errors = compilation.error_count - sum(1 for d in compilation.diagnostics if d.is_error)
    report.hidden += report.uncounted_errors
    report.lines = scanner.lines
    report.diagnostics.sort(key=lambda d: (d.span.line, d.span.column, d.code))
    return report
