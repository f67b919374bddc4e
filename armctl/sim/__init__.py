"""The simulated arm: a pure, event-driven model of the arm, its connector and the line
(``model.SimulatedArm``), and its thin real-time edges — the ``sim://`` pyserial URL
(``protocol_sim``) and the pty / TCP bridges (``bridge``).

The ``sim://`` scheme is registered with pyserial by ``armctl/__init__.py`` (which runs first
whenever this package is imported), so ``serial.serial_for_url("sim://?speed=4")`` works after
``import armctl``; nothing here imports pyserial.  ``SimulatedArm`` and ``SimOptions`` are
importable from here; the model modules are loaded only when first used.
"""

from __future__ import annotations

__all__ = ["SimOptions", "SimulatedArm"]


def __getattr__(name: str):
    if name in __all__:
        from . import model

        return getattr(model, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
