"""What the Python API hands back: a job's ``RunResult``, its ``Progress``, the arm's ``ArmStatus``.

Strategy: frozen values, built from the job engine's ``RunView`` (armctl/core/job.py) or the link's
state by one constructor each (``RunResult.of``, ``Progress.of``, ``ArmStatus.of``), so the API,
``armctl run --json`` and the server say the same thing in the same words.  The exit code of an
outcome is one rule (``exit_code_of``).
"""
from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import Callable, Mapping

from ..errors import EXIT_INTERRUPTED, EXIT_OK, EXIT_PROBLEMS

# status kinds behind each group of ArmStatus (armctl/core/protocol.py's STATUS_ROTATION)
_AGE_KINDS = {"position": (0,), "joints": (1, 2), "worktable": (3,), "pause_pwm": (4,), "wrist": (5,),
              "program": (100, 102, 103)}


@dataclass(frozen=True)
class RunResult:
    """How a job (or a move) ended — the one result: ``Arm.run`` returns it and ``armctl run
    --json`` prints it as its summary (``to_json``), both built by ``RunResult.of``.

    ``outcome``: "finished" (the arm's reports proved every frame executed), "finished, unproven"
    (the arm ended, but some frames rest on time alone and the FIFO size was never probed: a
    dropped frame would look the same), "interrupted" (``Arm.stop``, Ctrl-C), "failed", "port
    lost", "no confirmation", "frames may have been lost" or "paused by the script" (the script's own
    PAUSE paused the arm with lines still to run; ``resume_line`` is the line after it) (the API
    raises these five as ``JobFailed`` with this result attached); ``armctl run --json`` adds "refused" (the script's
    errors, nothing sent).  ``frames_by_reports`` / ``frames_by_time`` / ``frames_unseen``: the frames
    the arm's reports saw run, those confirmed by time alone (the slowest-arm bound), and those a
    report proves gone from the FIFO without seeing them run (a sighting on a later frame: a frame a
    full FIFO dropped would look the same).  Lines are the script's line numbers; the move of
    ``Arm.move`` is line 1.  ``last_line_executed``: the last line the arm's reports prove
    executed.  ``arm_time_s``: from the first frame to the arm at rest, in the arm's clock, to
    the millisecond (None when it did not come to rest at the job's last target: an interrupted
    job).  ``resume_line``: where ``run(..., from_line=)`` / ``--from-line`` continues the job
    (None when nothing is left); ``resume_command``: the ``armctl run`` command line that does it
    (None from the API: it knows no command line).  ``exit_code``: what ``armctl run`` exits with for this outcome.
    """

    outcome: str
    frames_sent: int
    total_frames: int
    last_line_sent: int | None
    last_line_executed: int | None
    arm_time_s: float | None
    estimated_job_s: float
    resume_line: int | None
    resume_command: str | None = None
    messages: tuple[str, ...] = ()
    exit_code: int = 0
    frames_by_reports: int = 0
    frames_by_time: int = 0
    frames_unseen: int = 0

    @property
    def finished(self) -> bool:
        return self.outcome == "finished"

    @classmethod
    def of(cls, view, outcome: str, lines, *, estimated_job_s: float,
           resume_command: Callable[[int], str] | None = None) -> RunResult:
        """The result of a job the runner drove: ``view`` its ``RunView``, ``lines`` the
        script's lines (the resume line moves out of repeat blocks), ``resume_command(line)``
        the command line that resumes it."""
        from .jobflow import resume_line

        resume = resume_line(view, lines) if outcome != "finished" else None
        arm_time_s = view.arm_time_s
        # the outcome as plain text (the engine's Outcome is a StrEnum): it prints and compares as documented
        return cls(str(outcome), view.frames_sent, view.total_frames, getattr(view.last_sent, "line", None),
                   getattr(view.last_done, "line", None), None if arm_time_s is None else round(arm_time_s, 3),
                   estimated_job_s, resume, None if resume is None or resume_command is None else resume_command(resume),
                   tuple(view.messages), exit_code_of(outcome), view.frames_by_reports, view.frames_by_time,
                   view.frames_unseen)

    @classmethod
    def nothing_sent(cls, outcome: str, *, exit_code: int | None = None, message: str | None = None,
                     total_frames: int = 0) -> RunResult:
        """A job that sent nothing: nothing left to send ("finished"), or (``armctl run``)
        refused, failed before the first frame, interrupted while starting (``total_frames``: the
        job's, when it is known)."""
        return cls(outcome, 0, total_frames, None, None, None if outcome != "finished" else 0.0, 0.0, None,
                   messages=() if message is None else (message,), exit_code=exit_code_of(outcome) if exit_code is None else exit_code)

    @classmethod
    def interrupted_before_start(cls, checked=None) -> RunResult:
        """A job stopped before its first frame (Ctrl-C, ``stop()`` while the arm is read or the
        job planned): nothing sent, of ``checked``'s frames (``CheckedScript.frames``: the
        estimate's count); None — a resume whose first line the arm's report has yet to decide:
        its total is not known (0)."""
        return cls.nothing_sent("interrupted", total_frames=(None if checked is None else checked.frames()) or 0)

    def to_json(self) -> dict:
        """The result as a JSON object's fields (``armctl run --json``'s summary)."""
        return {f.name: list(value) if isinstance(value, tuple) else value
                for f in fields(self) for value in (getattr(self, f.name),)}



def exit_code_of(outcome: str) -> int:
    """What ``armctl run`` exits with after a job that ended ``outcome`` (docs/cli.md's codes)."""
    return EXIT_OK if outcome == "finished" else EXIT_INTERRUPTED if outcome == "interrupted" else EXIT_PROBLEMS


@dataclass(frozen=True)
class Progress:
    """What ``on_progress`` is given, from the worker thread, whenever a frame was written or
    the frames known executed moved on, and at least every ``PROGRESS_EVERY_S`` (times in the
    arm's clock)."""

    frames_sent: int
    total_frames: int
    last_line_sent: int | None
    last_line_executed: int | None  # the last line the arm's reports prove executed
    elapsed_s: float
    eta_s: float
    position_mm: tuple[float, float, float] | None
    paused: bool | None  # as two agreeing reports say (a pause toggle acts after the frames queued before it)

    @classmethod
    def of(cls, view, paused: bool | None, now_s: float) -> Progress:
        """The job engine's ``view`` at ``now_s`` (the arm's clock)."""
        position = view.position_mm
        return cls(view.frames_sent, view.total_frames, getattr(view.last_sent, "line", None),
                   getattr(view.last_done, "line", None), now_s - view.started_s, view.eta_s,
                   None if position is None else tuple(position), paused)


@dataclass(frozen=True)
class ArmStatus:
    """The arm's decoded report: every value as last accepted (None until its kind was seen),
    and ``ages_s``: for each group of values, seconds since it was last reported."""

    position_mm: tuple[float, float, float] | None
    joints_deg: tuple[float | None, ...]
    worktable_mm: tuple[float | None, ...]
    wrist_deg: tuple[float | None, float | None]
    pwm_us: int | None
    paused: bool | None
    run_position: float | None
    ages_s: Mapping[str, float | None] = field(default_factory=dict)


    @classmethod
    def of(cls, state, now: float) -> ArmStatus:
        """The link's ``state`` (complete) as read at ``now`` (the link's clock)."""

        def age(kinds) -> float | None:
            seen = [state.last_seen[k] for k in kinds if k in state.last_seen]
            return now - min(seen) if seen else None

        return cls(position_mm=state.position_mm, joints_deg=tuple(state.joints_deg),
                   worktable_mm=tuple(state.worktable_mm), wrist_deg=(state.w0_deg, state.w1_deg),
                   pwm_us=state.pwm_us, paused=state.paused, run_position=state.run_position,
                   ages_s={name: age(kinds) for name, kinds in _AGE_KINDS.items()})
