"""What ``armctl probe`` keeps: the measured values stored with the arm (armctl/host/calibration.py),
``--write``'s ``[connector]`` naming the arm it was measured on, and ``--list`` / ``--forget``.

Strategy: the probe's findings go through ``report.to_write`` — the one choice of what is stated
(sure or likely) — into the store, dated and with their evidence; ``--write`` writes the same
values plus ``measured_on``, so a project file never applies to another arm.
"""

from __future__ import annotations

from datetime import datetime, timezone

import click

from ..host import calibration


def today() -> str:
    return datetime.now(timezone.utc).date().isoformat()


arm_identity = calibration.arm_identity


def stated(probe, kept: dict, say=lambda text: None) -> dict:
    """What ``probe`` states (``report.to_write``) to keep or write over ``kept``, what this arm's
    store or file holds: all of it, but a ``kinematics_verified`` false that one agreeing pose gave
    (likely: a probe without motion) over a true — one pose proves nothing against it — and a
    value the profile's own checks refuse (a FIFO of 2 frames, under the 3 armctl streams to:
    kept, it made every later command on the arm, this probe's included, exit 2), told to ``say``."""
    from .plan import LIKELY
    from .report import finding_for, to_write

    values = to_write(probe)
    if (values.get("kinematics_verified") is False and kept.get("kinematics_verified") is True
            and finding_for(probe, "kinematics_verified").confidence == LIKELY):
        del values["kinematics_verified"]
    for name, value in list(values.items()):
        refused = refusal(name, value)
        if refused is not None:
            del values[name]
            say(f"not kept: {refused}: armctl cannot drive this arm as measured")
    return values


def refusal(name: str, value) -> str | None:
    """Why the profile refuses ``value`` for the setting ``name`` (the schema's own words), or None."""
    from ..core.profile_schema import PROFILE_SCHEMA, check_profile_data
    from ..errors import ProfileError

    section = "connector" if name in PROFILE_SCHEMA["connector"] else "timing"
    try:
        check_profile_data({section: {name: value}}, "probe")
    except ProfileError as error:
        return str(error).removeprefix("probe: ")
    return None


def keep(port: str, arm: str, probe, say) -> None:
    """Store what ``probe`` found for ``arm``, probed through ``port``."""
    from .report import finding_for

    earlier = calibration.load(arm)
    values = stated(probe, {} if earlier is None else earlier.values(), say)
    findings = [(name, value, finding_for(probe, name).evidence, finding_for(probe, name).confidence)
                for name, value in values.items()]
    if findings:
        path = calibration.save(calibration.calibration_of(port, arm, findings, today(), probe.baud))
        say(f"kept for {arm} in {path}: every command on this arm uses it (armctl probe --list)")


def written(arm: str, values: dict) -> dict:
    """``--write``'s ``[connector]``: the values and the arm they were measured on."""
    from ..host.profile import MEASURED_ON

    return {MEASURED_ON: arm, **values}


def measured_elsewhere(table: dict, arm: str, values: dict) -> list[str]:
    """The settings an armctl.toml's ``[connector]`` ``table`` holds from a probe of another arm than
    ``arm`` (its ``measured_on``) that ``values`` does not replace: ``--write`` takes them out, or
    they would name ``arm`` (a probe without motion of arm B left arm A's command_overhead_s)."""
    from ..host.profile import MEASURED_ON
    from . import SETTINGS

    measured_on = table.get(MEASURED_ON)
    if not isinstance(measured_on, str) or measured_on_arm(table, arm):
        return []
    return [name for name in SETTINGS if name in table and name not in values]


def measured_on_arm(table: dict, arm: str) -> bool:
    """Whether an armctl.toml's ``[connector]`` ``table`` names ``arm`` as the one it was measured on."""
    from ..errors import ConfigError
    from ..host.profile import MEASURED_ON

    try:
        return isinstance(table.get(MEASURED_ON), str) and arm_identity(table[MEASURED_ON]) == arm
    except ConfigError:  # (a bad sim:// URL: not this arm)
        return False


def list_stored(as_json: bool) -> int:
    records = calibration.stored()
    if as_json:
        import json

        click.echo(json.dumps({c.arm: c.to_json() for c in records}, indent=2, ensure_ascii=False))
        return 0
    if not records:
        click.echo(f"no arm probed yet (the store is {calibration.store_dir()})")
        return 0
    for record in records:
        click.echo(f"{record.arm}  (last probed through {record.port})")
        for name, measured in record.settings.items():
            value = str(measured.value).lower() if isinstance(measured.value, bool) else measured.value
            click.echo(f"    {name} = {value}  (probed on {measured.probed_on}, {measured.confidence or 'measured'})")
    click.echo(f"store: {calibration.store_dir()}")
    return 0


def forget_arm(arm_or_port: str | None, port: str | None) -> int:
    """``--forget [ARM]``: ARM is an identity or a port; none given: the arm on ``--port`` (or
    the configured port)."""
    from ..errors import UsageFailure
    from ..host.link import choose_port

    if arm_or_port is not None and not arm_or_port.strip():  # `--forget "$ARM"`, ARM unset: not the arm on the port
        raise UsageFailure(f"--forget {arm_or_port!r} names no arm: give one as `armctl probe --list` names it, "
                           "or a port, or --forget alone for the arm on --port")
    target = arm_or_port or choose_port(port).url
    arm = calibration.arm_identity(target)
    if calibration.forget(arm):
        click.echo(f"forgot the calibration of {arm}")
        return 0
    click.echo(f"nothing stored for {arm} (armctl probe --list shows what is)", err=True)
    return 1
