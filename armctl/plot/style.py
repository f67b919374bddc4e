"""How the plot looks, shared by the HTML and the static renderers: colours and names.

Strategy: one table per visual fact, so the interactive and the static picture of one job
use the same colour for the same statement kind and the same words in their legends.
"""

from __future__ import annotations

from .path import APPROXIMATE_NOTE, KIND_LABELS

# Colour-blind-safe (Okabe-Ito) colours per statement kind.
KIND_COLORS = {
    "linear": "#0072B2",  # blue
    "accel": "#56B4E9",  # sky blue
    "arc": "#009E73",  # green
    "joint": "#CC79A7",  # purple: drawn dashed, being approximate
    "still": "#E69F00",  # orange markers
}
SEVERITY_COLORS = {"error": "#D55E00", "warning": "#B8860B"}
START_COLOR = "#000000"
WORKSPACE_COLOR = "#9E9E9E"
AXIS_TITLES = {"x": "X (mm)", "y": "Y (mm)", "z": "Z (mm)"}
VIEW_TITLES = {"xy": "top view (X/Y)", "xz": "front view (X/Z)", "yz": "side view (Y/Z)", "3d": "3D"}
STATIC_VIEWS = ("xy", "xz", "yz")


def kind_name(kind: str) -> str:
    """The legend's name for a statement kind (the joint kind says why it is approximate)."""
    label = KIND_LABELS[kind]
    return f"{label}: {APPROXIMATE_NOTE}" if kind == "joint" else label


def start_name() -> str:
    return "start: the profile's fixed pose 0"


def workspace_name(box) -> str:
    return (f"workspace box X {box.x_mm[0]:g}…{box.x_mm[1]:g}, Y {box.y_mm[0]:g}…{box.y_mm[1]:g},"
            f" Z {box.z_mm[0]:g}…{box.z_mm[1]:g} mm")


def findings_name(severity: str, count: int) -> str:
    return f"lint {severity}{'' if count == 1 else 's'} ({count})"


def counted(count: int, noun: str) -> str:
    return f"{count} {noun}{'' if count == 1 else 's'}"


def summary(path) -> str:
    """``14 segments (linear 11, arc 2, joint 1), 0 findings``."""
    kinds = ", ".join(f"{kind} {len(path.of_kind(kind))}" for kind in path.kinds) or "nothing moves"
    return f"{counted(len(path.segments), 'segment')} ({kinds}), {counted(len(path.findings), 'finding')}"


def title(path) -> str:
    where = f" from line {path.from_line}" if path.from_line > 1 else ""
    return f"{path.file}{where}: {summary(path)}"

