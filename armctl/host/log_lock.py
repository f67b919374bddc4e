"""The locks on a job's ``--log``: a run holds one on its log while its job runs, a resume on the
log it resumes (``resume_claim``), so that no two processes decide from the same records and send
the same lines twice.

Strategy: ``flock`` on the open file — the kernel drops it when the process ends, kill -9
included, so a crashed run never leaves a log locked; where nothing can be locked (no fcntl on
Windows, a file system without locks) the log goes unlocked, as before locks.
"""

from __future__ import annotations

from contextlib import contextmanager


IN_USE = ("the job it records is still running, or another armctl is resuming it: it holds the lock a run keeps on "
          "its --log, and a resume on the log it resumes, while its job runs; let that job end, or stop it (Ctrl-C), "
          "then resume")


def locked(log, shared: bool = False) -> bool:
    """An exclusive lock (``shared``: a shared one) on the open file ``log`` for as long as it is
    open (the kernel drops it when the process ends, kill -9 included); False when another process
    holds one that excludes it.  Where nothing can be locked (no fcntl on Windows, a file system
    without locks), True: the file goes unlocked.  A run's --log is locked so (ui/run_job.py), and
    a log a resume reads (``resume_claim``); ``journal_in_use`` asks for a shared one."""
    try:
        import fcntl
    except ImportError:
        return True
    try:
        fcntl.flock(log.fileno(), (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
    except BlockingIOError:
        return False
    except OSError:  # ENOLCK, EOPNOTSUPP…: unlocked, as before locks
        return True
    return True


@contextmanager
def resume_claim(log, words=None):
    """``log`` (the path a resume reads, after ``read_resume_point``) locked while the resumed
    job runs, as a run locks its --log: another resume of it at the same time — it would decide
    from the same records and send the same lines again — is refused (``ResumeRefused``, exit 2,
    nothing sent; told in ``words``, ``resume_words``: the CLI's by default).  Nothing to lock for a
    ``ResumePoint``, or where nothing can be locked."""
    import os

    if not isinstance(log, (str, os.PathLike)):
        yield
        return
    from ..errors import ResumeRefused
    from .resume_words import CLI

    try:
        held = open(log, "rb")  # a regular file: read_resume_point read it
    except OSError:
        yield
        return
    with held:
        if not locked(held):
            raise ResumeRefused(f"{(words or CLI).naming(log)}: {IN_USE}")
        yield


def journal_in_use(path: str) -> bool:
    """Another process holds the lock ``armctl run --log`` keeps on its log while its job runs
    (``locked``, as ui/run_job.py takes it): that job is not over, whatever its log says yet.  False
    where nothing can be locked (no fcntl, a file system without locks)."""
    try:
        with open(path, "rb") as probe:
            return not locked(probe, shared=True)  # (released as the file closes)
    except OSError:
        return False


def same_journal(log, resume) -> bool:
    """``log`` (an open file) is the file ``resume`` (a path; anything else: no) names."""
    import os

    if not isinstance(resume, (str, os.PathLike)):
        return False
    try:
        return os.path.samestat(os.fstat(log.fileno()), os.stat(resume))
    except (AttributeError, OSError, ValueError):
        return False
