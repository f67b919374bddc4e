"""The words a refused resume is told in: those of the interface that asked for it —
``armctl run --resume LOG`` (``CLI``), ``Arm.run(resume=)`` (``API``), ``armctl serve``'s
``POST …/jobs?resume=ID`` (``served``).

Strategy: each refusal is written once (jobflow.read_resume_point, resume_port, log_lock) with a
``ResumeWords`` passed in; only how the log, the line and the port are named and how a job is
started again differ between interfaces, never the reason — so no message is kept in three copies.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import PurePath


@dataclass(frozen=True)
class ResumeWords:
    resume: str  # the log asked for, "{log}" its path and "{job}" its name without suffix
    bare: str  # the same with no log named
    from_line: str  # the line to start at, which a resume decides itself
    on_port: str  # "{port}": resume on the arm there
    on_logged_port: str  # "{port}": resume on the port the log records
    give_port: str  # the way to name the port of an arm kept elsewhere
    again: str  # start the job again from its beginning

    def naming(self, log) -> str:
        """The log ``log`` (a path; None: no path known) as the interface names it."""
        if log is None:
            return self.bare
        path = os.fspath(log)
        return self.resume.format(log=path, quoted=repr(path), job=PurePath(path).stem)


CLI = ResumeWords(resume="--resume {log}", bare="--resume", from_line="--from-line", on_port="resume with --port {port}",
                  on_logged_port="leave out --port to resume on {port}", give_port="give its port as --port",
                  again="run the job again")

API = ResumeWords(resume="resume={quoted}", bare="resume=", from_line="from_line", on_port="resume on Arm.open({port!r})",
                  on_logged_port="resume on Arm.open({port!r})", give_port="open its port: Arm.open(PORT)",
                  again="run the job again")


def served(arm: str) -> ResumeWords:
    """``armctl serve``'s words for its arm named ``arm``: a job of its journal resumed by id."""
    serve = f"serve that arm: armctl serve --arm {arm}={{port}}"
    return ResumeWords(resume="?resume={job}", bare="?resume=", from_line="a line of your own", on_port=serve,
                       on_logged_port=serve, give_port=f"serve its port: armctl serve --arm {arm}=PORT",
                       again=f"start the job again: POST /api/arms/{arm}/jobs")
