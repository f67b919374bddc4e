"""armctl — drive a 6-axis desktop robot arm over its serial connector.

Importing armctl is cheap on purpose: heavy modules (lark, rich, serial) are imported by the
commands that need them, so ``armctl --help`` stays fast.  The Python API (docs/api.md) —
``from armctl import Arm`` — is imported on first use of one of its names (``__getattr__``).
"""

import sys

__version__ = "0.1.0"

# name → the module that defines it, imported when the name is first used
_API = {
    "Arm": "armctl.host.api", "ArmStatus": "armctl.host.api", "ArmTimeout": "armctl.host.api", "Progress": "armctl.host.api",
    "RunResult": "armctl.host.api", "JobObserver": "armctl.host.api", "JobFailed": "armctl.host.jobflow",
    "ArmctlError": "armctl.errors", "ConfigError": "armctl.errors", "PortError": "armctl.errors",
    "ProfileError": "armctl.errors", "ScriptError": "armctl.errors", "ResumeRefused": "armctl.errors",
    # the values docs/api.md names, here so that user code does not depend on the package's layout
    "CheckedScript": "armctl.core.checked", "CheckedJob": "armctl.core.checked", "check": "armctl.core.checked",
    "ScriptSnapshot": "armctl.script", "PortChoice": "armctl.host.link", "ResumePoint": "armctl.core.joblog",
    "JournalDamaged": "armctl.core.joblog", "NotProven": "armctl.core.joblog",
    "read_resume_point": "armctl.host.jobflow",
}
# written out, not computed: type checkers read __all__ statically (mypy --strict's "explicitly
# export"); tests/test_newcomer_typing.py holds it to _API
__all__ = [
    "Arm", "ArmStatus", "ArmTimeout", "ArmctlError", "CheckedJob", "CheckedScript", "ConfigError", "JobFailed",
    "JobObserver", "JournalDamaged", "NotProven", "PortChoice", "PortError", "ProfileError", "Progress", "ResumePoint",
    "ResumeRefused", "RunResult", "ScriptError", "ScriptSnapshot", "check", "read_resume_point",
]

TYPE_CHECKING = False  # true for type checkers; not typing's, whose import costs milliseconds here
if TYPE_CHECKING:  # what type checkers and IDEs see; at run time __getattr__ imports them
    from .host.api import Arm, ArmStatus, ArmTimeout, JobObserver, Progress, RunResult
    from .core.checked import CheckedJob, CheckedScript, check
    from .core.joblog import JournalDamaged, NotProven, ResumePoint
    from .errors import ArmctlError, ConfigError, PortError, ProfileError, ResumeRefused, ScriptError
    from .host.jobflow import JobFailed, read_resume_point
    from .host.link import PortChoice
    from .script import ScriptSnapshot


def __getattr__(name: str):
    module = _API.get(name)
    if module is None:
        raise AttributeError(f"module 'armctl' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # once: the next lookup does not come here
    return value


def __dir__() -> list:
    return sorted(set(globals()) | set(_API))


def _add_sim_scheme(serial_module) -> None:
    if "armctl.sim" not in serial_module.protocol_handler_packages:
        serial_module.protocol_handler_packages.append("armctl.sim")


class _AddSimSchemeWhenSerialLoads:
    """Make ``serial.serial_for_url("sim://…")`` reach armctl's simulator (pyserial's documented
    extension point: a package of ``protocol_<scheme>.py`` modules) without importing pyserial
    here: ``import armctl`` stays cheap, and the scheme is added the moment pyserial loads."""

    def find_spec(self, name, path=None, target=None):
        if name != "serial":
            return None
        import importlib.util

        sys.meta_path.remove(self)
        spec = importlib.util.find_spec("serial")
        if spec is not None and spec.loader is not None:
            load = spec.loader.exec_module

            def exec_module(module):
                load(module)
                _add_sim_scheme(module)

            spec.loader.exec_module = exec_module
        return spec


def _register_sim_scheme() -> None:
    if "serial" in sys.modules:
        _add_sim_scheme(sys.modules["serial"])
    elif not any(isinstance(f, _AddSimSchemeWhenSerialLoads) for f in sys.meta_path):
        sys.meta_path.insert(0, _AddSimSchemeWhenSerialLoads())


_register_sim_scheme()
