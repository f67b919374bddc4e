"""The job engine's own CPU on issue 23's 24,000-frame job, replayed: no simulator, no host.

``virtual_run.py --split`` counts the engine inside a whole run, where the simulator, the host
and the counters share the caches and the load of the machine moves every figure by several
per cent.  Here one run (``virtual_run.one_run``, the job of ``--cost``) records what the engine
was given — every ``Job.receive_statuses`` (the frames and their times), ``next_action`` and
``wrote``, with the copies of the streamer and the view the ``Job`` was made with and the
statements it took — and the engine alone is then driven through the same calls on fresh
copies, several times: only those replays are timed (CPU, ``time.process_time``).  A first,
untimed replay checks that every answer is the recorded one (the same ``Write``, ``Wait`` time,
``Done``, news place), else it stops: a replay that went another way would time another job
(the engine is pure: the timed ones, on the same calls, answer the same).

    .venv/bin/python benchmarks/engine_replay.py              # 5 replays, the median
    .venv/bin/python benchmarks/engine_replay.py --replays 9

To compare two trees, run it from each in turn (``PYTHONPATH=TREE``), alternating, a few times,
with ``PYTHONHASHSEED=0`` (the same dict layouts in every process): under load, medians of such
processes still differ by a few per cent, less than the engine's share of ``--split`` does.
"""

from __future__ import annotations

import argparse
import copy
import gc
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import virtual_run  # noqa: E402  (the job and the run of --cost)

from armctl.core.job import Job  # noqa: E402

CALLS = ("receive_statuses", "next_action", "wrote")


def record() -> tuple[dict, list]:
    """One run of the 24,000-frame job: what its ``Job`` was made with, and every call to it
    (name, arguments, answer)."""
    made: dict = {}
    calls: list = []
    originals = {name: Job.__dict__[name] for name in ("__init__", *CALLS)}

    def init(job, streamer, statements, view, **options):
        made.update(streamer=copy.deepcopy(streamer), view=copy.deepcopy(view), options=options, statements=[])

        def taken():
            for statement in statements:
                made["statements"].append(statement)
                yield statement
        originals["__init__"](job, streamer, taken(), view, **options)

    def recorded(name):
        function = originals[name]

        def call(job, *args):
            answer = function(job, *args)
            calls.append((name, tuple(list(arg) if isinstance(arg, (list, tuple)) else arg for arg in args), answer))
            return answer
        return call

    try:
        Job.__init__ = init
        for name in CALLS:
            setattr(Job, name, recorded(name))
        with tempfile.TemporaryDirectory() as tmp:
            script = Path(tmp) / "job24k.txt"
            virtual_run.write_cost_job(script)
            virtual_run.one_run(script)
    finally:
        for name, function in originals.items():
            setattr(Job, name, function)
    return made, calls


def replay(made: dict, calls: list, check: bool = False) -> float:
    """CPU seconds of the engine answering ``calls`` afresh.  With ``check``, every answer is
    compared with the recorded one (untimed: kept answers would cost the collector what the
    engine's own, dropped by its host, do not); it stops at the first that differs."""
    job = Job(copy.deepcopy(made["streamer"]), iter(made["statements"]), copy.deepcopy(made["view"]),
              **made["options"])
    methods = {name: getattr(job, name) for name in CALLS}
    # The recording's objects (some million) out of the collector's sight: a full collection
    # would walk them all, a cost of this harness, not of the engine
    gc.collect()
    gc.freeze()
    try:
        start = time.process_time()
        if not check:
            for name, args, _ in calls:
                methods[name](*args)
        else:
            for k, (name, args, answer) in enumerate(calls):
                got = methods[name](*args)
                if got != answer:
                    raise SystemExit(f"call {k} ({name}{args!r}) answered {got!r}, recorded {answer!r}: "
                                     "not the same job")
        return time.process_time() - start
    finally:
        gc.unfreeze()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--replays", type=int, default=5)
    args = parser.parse_args()
    made, calls = record()
    replay(made, calls, check=True)  # the engine answers as it did in the run (and warms up)
    spent = [replay(made, calls) for _ in range(args.replays)]
    frames = sum(1 for name, _, _ in calls if name == "wrote")
    counts = ", ".join(f"{sum(1 for call in calls if call[0] == name)} {name}" for name in CALLS)
    median = statistics.median(spent)
    print(f"job engine alone, {frames} frames ({counts}): CPU median {median:.3f} s of {args.replays} replays "
          f"({', '.join(f'{s:.3f}' for s in spent)}), {median / frames * 1e6:.1f} µs a frame written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
