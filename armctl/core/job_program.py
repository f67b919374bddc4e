"""An SD program held mid-job: when the frames after its PROGRAM frame may go, and what the job
may claim of it.

Strategy: the host cannot see inside an SD program, so time never confirms its PROGRAM frame
(``Streamer.program_time_unknown``).  On an arm whose control frames queue (H5) the program holds
the FIFO while it runs, so the FIFO's bound holds the host once the frames behind it fill it; on
one where they act as they land (``control_frames = "arrival"``), rule (c) of the streamer
(armctl/core/streamer/__init__.py) holds the next control frame, which would cut the program
short.  Either way, unless a later frame's sighting confirms the program first, the job waits
for this part to say it is over.  What may be concluded, from what evidence:

- **Ran and ended** (``Arrival.program_ended``): the arm worked after the frame landed — a kind's
  reports agreed on a new value, two in a row (armctl/core/job_readings.py ``worked_after``), or
  the run position moved — and it rests since, wherever (the program moves the arm as it
  says), not paused.  The frames through the PROGRAM are confirmed by that evidence.
- **No report of its work** within as long as an SD program is waited for at the end of a job
  (``JobEnd.overrun_limit_s``, counted from its landing or from the user's last resume: a pause's
  time is not the program's): once the arm is at rest, the job goes on rather than wait for
  ever, and can end only ``finished, unproven``, naming the PROGRAM (``unproven``).
- **Neither** that proof **nor** such a rest within as long again: the arm still works (or
  reports that keep being corrupted interrupt every rest), so the job ends without sending
  more, saying which ``--from-line`` runs the rest.

Pure: ``now`` passed in, no I/O; the state is the programs the job went on after unseen and the
time the user's pause last held the job.
"""

from __future__ import annotations

import math

from .job_readings import landed_s
from .streamer.frames import Evidence, where


class ProgramWait:
    """The wait behind SD programs of one job (see the module docstring)."""

    def __init__(self, view, streamer, arrival, limit_s) -> None:
        """``limit_s()``: how long a program no report shows at work is waited for."""
        self.view, self.streamer, self.arrival, self.limit_s = view, streamer, arrival, limit_s
        self.unseen: list[tuple[str, float]] = []  # (the PROGRAM, the wait) the job went on after unseen
        self.held_by_pause_s = -math.inf  # the last time the user's pause held the job

    def held(self, program, now: float) -> float | str | None:
        """The job is held behind ``program`` (a PROGRAM frame at the head of the pending frames):
        None once it is confirmed (by its proof, or unproven after the wait), the time to look
        again, or why the job ends here without sending more."""
        arrival, readings = self.arrival, self.arrival.readings
        landed = landed_s(program)
        if arrival.program_ended(program, now):
            program.seen = True  # its reports: it ran
            self.streamer.confirm_all_done(now, program.index + 1, Evidence.PROGRAM_ENDED)
            return None
        wait_s = self.limit_s()
        look_s = max(landed, self.held_by_pause_s) + wait_s  # (a pause's time not counted)
        if now < look_s:
            return look_s
        name = f"PROGRAM {program.command.program} at {where(program)}"
        if not readings.worked_after(landed) and arrival.arm_at_rest(now) and readings.paused is False:
            self.unseen.append((name, wait_s))
            self.streamer.confirm_all_done(now, program.index + 1)
            return None
        final_s = look_s + wait_s
        if now < final_s:
            return final_s
        line = getattr(self.view.next_statement, "line", None)
        why = ("on this arm a control frame would cut the program short as it lands" if self.streamer.control_on_arrival
               else "the frames written after it fill the arm's FIFO until it ends")
        return (f"{name} did not end in the {final_s - landed:.0f} s armctl waited for it (the arm still "
                f"working, or paused): the rest of the job was not sent, since {why}"
                + (f"; once it has ended, --from-line {line} runs the rest" if line is not None else ""))

    def unproven(self) -> list[str]:
        """Why the job's finish is unproven by the programs it went on after unseen (none: [])."""
        return [f"no report showed {name} running (its run position never moved, nor the arm) in the "
                f"{wait_s:.0f} s armctl waits for an SD program: the job went on, and had it still been "
                "running, the control frame after it cut it short" for name, wait_s in self.unseen]
