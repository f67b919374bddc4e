"""What the probe found, for people (a table) and programs (one JSON object), and the values
``--write`` puts into armctl.toml.

Strategy: one reading of the findings (``settings``) feeds all three outputs.  A value is
stated only when the probe is sure of it, or likely (a lower bound of the FIFO, kinematics
that agree at one pose only): an unsure or unmeasured setting is ``null`` in JSON, ``—`` in the
table and is not written.  JSON keys: exactly the seven settings, plus ``details``.
"""

from __future__ import annotations

from . import SETTINGS
from .plan import LIKELY, NOT_MEASURED, SURE, Finding
from .steps import DOCUMENTED

MEANING = {
    "fifo_frames": "frames the connector holds, the one executing included",
    "control_frames": "queued (H5): pause/reset wait in the FIFO; arrival: they act at once",
    "status_xyz_frame": "the frame status X/Y/Z (kind 0) uses after G54",
    "speed_factor": "the arm's motion time ÷ the model's",
    "kinematics_verified": "the profile's kinematics explain the reported joints and X/Y/Z",
    "speed_tolerance": "how much slower (or faster) than speed_factor the arm may run: the time bound's factor",
    "command_overhead_s": "the arm's wait before every motion command ([timing]; written in [connector])",
}


def finding_for(probe, name: str) -> Finding:
    found = probe.finding(name)
    if found is not None:
        return found
    why = "not measured: needs motion (run without --no-motion)" if name in ("speed_factor", "speed_tolerance", "command_overhead_s") \
        and not probe.motion_allowed \
        else "not measured (the probe stopped before it)"
    return Finding(name, DOCUMENTED.get(name), None, why, NOT_MEASURED)


def settings(probe) -> dict:
    """The seven settings: the measured value, or None when not measured or unsure."""
    values = {}
    for name in SETTINGS:
        found = finding_for(probe, name)
        values[name] = found.value if found.confidence in (SURE, LIKELY) else None
    return values


def to_write(probe) -> dict:
    return {name: value for name, value in settings(probe).items() if value is not None}


def as_json(probe) -> dict:
    rows = [finding_for(probe, name) for name in SETTINGS]
    extra = [f for f in probe.findings if f.name not in SETTINGS]
    details = {f.name: {"default": f.default, "measured": f.value, "evidence": f.evidence, "confidence": f.confidence,
                        **({"data": f.details} if f.details else {})} for f in rows + extra}
    details["arm_time_s"] = round(probe.arm_time_s, 3)
    details["restored"] = list(probe.notes)
    details["stopped"] = str(probe.stopped) if probe.stopped else None
    details["interrupted"] = probe.interrupted
    return {**settings(probe), "details": details}


def _shown(value) -> str:
    if value is None:
        return "—"
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)


def table_rows(probe) -> list[tuple[str, str, str, str, str]]:
    """(setting, documented default, measured, how sure, evidence) for every finding."""
    rows = [finding_for(probe, name) for name in SETTINGS]
    rows += [f for f in probe.findings if f.name not in SETTINGS]
    return [(f.name, _shown(f.default), _shown(f.value), f.confidence, f.evidence) for f in rows]


def print_table(console, probe) -> None:
    from rich.table import Table

    table = Table(title="armctl probe", show_lines=True)
    for column in ("setting", "documented", "measured", "how sure", "evidence"):
        table.add_column(column, overflow="fold")
    for row in table_rows(probe):
        table.add_row(*row)
    console.print(table)


def print_lines(say, probe) -> None:
    """The table as plain lines (not a terminal): one line per setting, its evidence below."""
    for name, default, measured, sure, evidence in table_rows(probe):
        say(f"{name}: {measured} ({sure}; documented: {default})")
        say(f"    {evidence}")
