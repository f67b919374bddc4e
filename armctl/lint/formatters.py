"""How lint's findings are written: text for people, JSON for tools, workflow commands for GitHub.

Strategy: a formatter is an object fed one ``FileReport`` at a time (``file(report)``) that
returns the text to write for it, then ``close(summary)`` for the text that ends the output —
so findings stream out file by file and nothing is held across files.  The command decides
where the text goes (stdout; the JSON formatter's summary goes to stderr, keeping stdout one
JSON document).  Pure: strings in, strings out.

- text: ruff-like ``file:line:col: CODE message``, the source line, a caret under the span,
  the hint (``Diagnostic.render()``), then a summary line.
- json: one array of objects ``{file, line, column, end_line, end_column, code, severity,
  message, hint}`` (columns 1-based, ``end_column`` exclusive; a span never crosses lines).
- github: ``::error file=…,line=…,endLine=…,col=…,endColumn=…,title=…::message`` (``::warning``
  for warnings) escaped as GitHub's toolkit does, then the same summary as text.
"""

from __future__ import annotations

import json
from collections import Counter
from dataclasses import dataclass, field

from ..script import Diagnostic
from .registry import rule_name


@dataclass
class Summary:
    """Totals over every input of one run."""

    files: int = 0  # scripts linted
    files_with_findings: int = 0
    errors: int = 0
    warnings: int = 0
    hidden: int = 0
    unreadable: int = 0  # paths that could not be read (missing, unreadable, no scripts)
    counts: Counter = field(default_factory=Counter)
    severities: Counter = field(default_factory=Counter)  # (code, severity) → findings

    def add(self, report) -> None:
        self.files += 1
        self.files_with_findings += bool(report.errors or report.warnings)
        self.errors += report.errors
        self.warnings += report.warnings
        self.hidden += report.hidden
        self.counts.update(report.counts)
        self.severities.update(report.severities)


def _plural(count: int, word: str) -> str:
    return f"{count:,} {word}{'' if count == 1 else 's'}"


def summary_line(summary: Summary) -> str:
    checked = _plural(summary.files, "file")
    if not summary.files:
        line = "No scripts checked."
    elif not summary.errors and not summary.warnings:
        line = f"All checks passed ({checked} checked)." if not summary.unreadable else f"No problems in {checked} checked."
    else:
        found = " and ".join(_plural(n, w) for n, w in ((summary.errors, "error"), (summary.warnings, "warning")) if n)
        line = f"Found {found} in {summary.files_with_findings:,} of {checked}."
    if summary.unreadable:
        line += f" {_plural(summary.unreadable, 'path')} could not be read (see above)."
    if summary.hidden:
        line += f" {summary.hidden:,} not shown (lint keeps the first findings of each file; --statistics counts all)."
    return line


def statistics_lines(severities: Counter) -> list[str]:
    """ruff-like: count, code, severity, rule name — most frequent first.  ``severities`` counts
    (code, severity): a code's findings on illustrative profile numbers are warnings, a row apart."""
    rows = sorted(severities.items(), key=lambda item: (-item[1], item[0]))
    width = max((len(f"{n:,}") for _, n in rows), default=1)
    return [f"{n:>{width},}  {code}  [{severity}]  {rule_name(code)}" for (code, severity), n in rows]


class TextFormatter:
    def __init__(self, max_width: int = 100) -> None:
        self.max_width = max_width

    def file(self, report) -> str:
        return "".join(d.render(self.max_width) + "\n\n" for d in report.diagnostics)

    def close(self, summary: Summary) -> str:
        return summary_line(summary) + "\n"


class JsonFormatter:
    """One JSON array, written as it grows: ``[`` before the first object, ``]`` at the end."""

    def __init__(self) -> None:
        self._count = 0

    def file(self, report) -> str:
        parts = []
        for diagnostic in report.diagnostics:
            parts.append(("[\n  " if self._count == 0 else ",\n  ") + json.dumps(as_record(diagnostic), ensure_ascii=False))
            self._count += 1
        return "".join(parts)

    def close(self, summary: Summary) -> str:
        return "[]\n" if self._count == 0 else "\n]\n"


def as_record(diagnostic: Diagnostic) -> dict:
    span = diagnostic.span
    return {
        "file": span.file, "line": span.line, "column": span.column, "end_line": span.line,
        "end_column": span.end_column, "code": diagnostic.code, "severity": diagnostic.severity,
        "message": _text(diagnostic.message), "hint": None if diagnostic.hint is None else _text(diagnostic.hint),
    }


def _text(value: str) -> str:
    """Lone surrogates (undecodable bytes) cannot be encoded as UTF-8 JSON: show U+FFFD."""
    return value.encode("utf-8", "replace").decode("utf-8") if not value.isascii() else value


class GithubFormatter:
    def file(self, report) -> str:
        return "".join(github_command(d) + "\n" for d in report.diagnostics)

    def close(self, summary: Summary) -> str:
        return summary_line(summary) + "\n"


def github_command(diagnostic: Diagnostic) -> str:
    span = diagnostic.span
    kind = "error" if diagnostic.is_error else "warning"
    properties = {
        "file": span.file, "line": span.line, "endLine": span.line, "col": span.column,
        "endColumn": max(span.end_column, span.column), "title": f"armctl {diagnostic.code}",
    }
    message = diagnostic.message  # the title names the code
    if diagnostic.hint:
        message += f"\nhint: {diagnostic.hint}"
    props = ",".join(f"{key}={escape_property(str(value))}" for key, value in properties.items())
    return f"::{kind} {props}::{escape_data(_text(message))}"


def escape_data(text: str) -> str:
    """GitHub's escaping of a workflow command's message (actions/toolkit ``escapeData``)."""
    return text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")


def escape_property(text: str) -> str:
    """GitHub's escaping of a property value (``escapeProperty``): also ``:`` and ``,``."""
    return escape_data(_text(text)).replace(":", "%3A").replace(",", "%2C")


FORMATTERS = {"text": TextFormatter, "json": JsonFormatter, "github": GithubFormatter}
