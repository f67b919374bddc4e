"""Record the golden diagnostics the lint differential test (tests/test_lint_golden.py) holds
lint to: ``python tests/data/lint/golden/record.py``.  Run it only when a finding is meant to
change (a new rule, a reworded message), never to make a speed-up pass: the point of the file
is that a faster lint says exactly what the slow one said."""

from __future__ import annotations

import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
sys.path.insert(0, str(ROOT))

# (script, profile or None for the packaged default), paths relative to the repository root
CORPUS = [
    ("tests/data/lint/every_rule.txt", "tests/data/lint/profile.toml"),
    ("tests/data/lint/golden/geometry.txt", None),
    *((f"scripts/{path.name}", None) for path in sorted((ROOT / "scripts").glob("*.txt"))),
]
GOLDEN = HERE / "diagnostics.json"


def diagnostics(script: str, profile_path) -> dict:
    """What lint reports on ``script`` (every finding kept), as plain data."""
    from armctl.lint.engine import lint_lines
    from armctl.host.profile import default_profile, load_profile
    from armctl.script.files import iter_lines

    profile = default_profile() if profile_path is None else load_profile(ROOT / profile_path)
    with open(ROOT / script, "rb") as stream:
        report = lint_lines(iter_lines(stream, name=script), script, profile, max_diagnostics=1_000_000)
    return {
        "errors": report.errors, "warnings": report.warnings, "hidden": report.hidden,
        "diagnostics": [[d.span.line, d.span.column, d.span.end_column, d.code, d.severity,
                         d.message, d.hint] for d in report.diagnostics],
    }


def record() -> dict:
    return {f"{script} {profile or 'default'}": diagnostics(script, profile) for script, profile in CORPUS}


if __name__ == "__main__":
    # one finding a line, so that a change shows as a small diff
    rows = []
    for key, found in record().items():
        rows.append(f"{json.dumps(key)}: {{" + ", ".join(f'"{k}": {found[k]}' for k in ("errors", "warnings", "hidden"))
                    + ', "diagnostics": [\n' + ",\n".join(json.dumps(d, ensure_ascii=False) for d in found["diagnostics"])
                    + "]}")
    GOLDEN.write_text("{\n" + ",\n".join(rows) + "\n}\n", encoding="utf-8")
    print(f"wrote {GOLDEN.relative_to(ROOT)}")
