"""armctl lint: every check on a motion script before anything moves — for people and for CI.

Strategy: lint is the compiler's pass plus rules.  The language's own diagnostics (E0xx,
``armctl.script.RULES``) come from compiling the script as a stream; lint's rules (L1xx…L5xx)
judge the compiled statements against the arm profile while a tracker follows where the arm
will be.  Pure except for ``paths`` (the file system) and ``command`` (click).

Modules, one job each:
  registry.py    the code table (RULES: language + lint, declared statically), @check, --select/--ignore Selection
  rules.py       lint's rule functions (geometry, speeds, PWM, end state)
  tracker.py     where the arm will be between statements (G54 origin, FK after G6/POSE, PWM, pause)
  scan.py        what the source text says (parameters read/assigned, repeat counts, inline ignores)
  engine.py      one script → FileReport (streaming; bounded memory)
  paths.py       files, directories (recursive, by pattern), - for stdin
  formatters.py  text (ruff-like), json, github workflow commands; summary and statistics
  command.py     the click command ``lint`` (registered by armctl/ui/cli.py)

Usage::

    from armctl.lint import lint_lines, Selection
    from armctl.host.profile import load_profile

    report = lint_lines(open("job.txt"), "job.txt", load_profile(), Selection.of(ignore=["L203"]))
    for diagnostic in report.diagnostics:
        print(diagnostic.render())
"""

# Exports are loaded on first use (PEP 562): `armctl --help` imports armctl.lint.command,
# and that must not pull in the engine, the compiler and lark.
_EXPORTS = {
    "FileReport": "engine", "lint_lines": "engine",
    "LINT_RULES": "registry", "RULES": "registry", "Selection": "registry", "UnknownCode": "registry",
    "rule_name": "registry",
}


def __getattr__(name):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'armctl.lint' has no attribute {name!r}")
    import importlib

    return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)

__all__ = ["FileReport", "LINT_RULES", "RULES", "Selection", "UnknownCode", "lint_lines", "rule_name"]
