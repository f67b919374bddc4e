"""The simulated arm: a pure, event-driven model of the arm, its connector and the line
(``model.SimulatedArm``), and its thin real-time edges — the ``sim://`` pyserial URL
(``protocol_sim``) and the pty / TCP bridges (``bridge``).

Importing this package registers the ``sim://`` scheme with pyserial (it appends
``armctl.sim`` to ``serial.protocol_handler_packages`` once), so ``serial.serial_for_url(
"sim://?speed=4")`` works after ``import armctl.sim``.  ``SimulatedArm`` and ``SimOptions``
are importable from here; the model modules are loaded only when first used.
"""

from __future__ import annotations

try:
    import serial as _serial
except ImportError:  # pragma: no cover - pyserial is a dependency; the model works without it
    _serial = None
else:
    if __name__ not in _serial.protocol_handler_packages:
        _serial.protocol_handler_packages.append(__name__)

__all__ = ["SimOptions", "SimulatedArm"]


def __getattr__(name: str):
    if name in __all__:
        from . import model

        return getattr(model, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
