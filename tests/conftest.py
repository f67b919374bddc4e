"""Shared test plumbing.

Golden frame vectors (tests/data/golden_*.txt, written by hand from PROTOCOL.md; the format
is described at the top of each file).  A test that takes ``command_vector`` or
``status_vector`` runs once per record; ``all_command_vectors`` / ``all_status_vectors`` give
the whole list.  The files are read lazily, so a broken data file fails only these tests.

No test can hang: pyproject.toml gives every test a timeout (pytest-timeout, ``thread``
method, which needs no signal).  Tests that run on the wall clock (bridges, signals to a
subprocess, a ``sim://`` without ``clock=virtual``) carry the ``realtime`` marker:
``pytest -m "not realtime"`` deselects them, and ``ARMCTL_SKIP_REALTIME=1`` skips them.
A test that presses Ctrl-C in its own process takes the ``ctrl_c`` fixture, which works however
the runner was started (nohup, ``&``, CI with SIGINT ignored).
"""

from __future__ import annotations

import functools
import os
import re
import signal
import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

import armctl.core.protocol as protocol
import armctl.core.status_frames as status_frames

# The user's own armctl.toml (~/.config/armctl/armctl.toml) must not change what the tests see:
# every test, and every armctl it starts, looks in an empty config directory instead.  Tests of
# the user file point XDG_CONFIG_HOME elsewhere with monkeypatch.
os.environ["XDG_CONFIG_HOME"] = tempfile.mkdtemp(prefix="armctl-test-config-")
# Likewise the user data directory, where ``armctl probe`` keeps what it measured with the arm
# (armctl/host/calibration.py): here for the whole session, and a fresh one for each test (below), so
# a test that probes an arm changes no other test's run on that arm.
os.environ["XDG_DATA_HOME"] = tempfile.mkdtemp(prefix="armctl-test-data-")

DATA = Path(__file__).parent / "data"

# The suite runs in parallel processes (README: ``pytest -n 4`` on 2 cores), so a test's CPU time
# is no measure of its wall time: no Hypothesis example has a deadline and none is judged too slow
# (every test still has its pytest-timeout limit). A test's own @settings keeps what it names.
settings.register_profile("armctl", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("armctl")

# "a[3..6]   00 00 c8 42   comment": a byte range, its bytes, then two spaces and free text.
_BYTES_LINE = re.compile(r"a\[(\d+)(?:\.\.(\d+))?\]\s+([0-9a-f]{2}(?: [0-9a-f]{2})*)(?:\s{2,}.*)?")


@dataclass(frozen=True)
class GoldenVector:
    name: str
    call: str  # the constructor call exactly as written in the file
    obj: object  # that call, evaluated with armctl.core.protocol's names
    data: bytes
    decode_only: bool  # bytes → object only (e.g. a linear move with a[2]=0)
    where: str  # "file:line", for failure messages

    def __repr__(self) -> str:
        return f"<{self.name} at {self.where}>"


@functools.cache
def load_golden(filename: str, frame_size: int) -> tuple[GoldenVector, ...]:
    path = DATA / filename
    records: list[dict] = []
    for number, raw in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        line = raw.rstrip()
        where = f"{path.name}:{number}"
        if not line or line.startswith("#"):
            continue
        if line.startswith("== "):
            name, *flags = line[3:].split()
            if set(flags) - {"decode-only"}:
                raise ValueError(f"{where}: unknown flag in {line!r}")
            records.append({"name": name, "decode_only": bool(flags), "call": [], "data": bytearray(), "where": where})
            continue
        if not records:
            raise ValueError(f"{where}: text before the first record")
        record = records[-1]
        if line.startswith("a["):
            match = _BYTES_LINE.fullmatch(line)
            if match is None:
                raise ValueError(f"{where}: cannot read byte line {line!r}")
            first = int(match[1])
            last = int(match[2]) if match[2] else first
            values = bytes.fromhex(match[3])
            if first != len(record["data"]) or len(values) != last - first + 1:
                raise ValueError(f"{where}: label a[{first}..{last}] does not fit {len(values)} byte(s) at offset {len(record['data'])}")
            record["data"] += values
        elif record["data"]:
            raise ValueError(f"{where}: call text after the bytes began")
        else:
            record["call"].append(line.strip())
    vectors = []
    for record in records:
        if len(record["data"]) != frame_size:
            raise ValueError(f"{record['where']}: {record['name']} has {len(record['data'])} bytes, not {frame_size}")
        call = " ".join(record["call"])
        names = {**vars(protocol), **vars(status_frames)}  # protocol's interface: status names load on first use
        obj = eval(call, {"__builtins__": {}}, names)  # noqa: S307 - our own data file
        vectors.append(GoldenVector(record["name"], call, obj, bytes(record["data"]), record["decode_only"], record["where"]))
    names = [v.name for v in vectors]
    if len(set(names)) != len(names):
        raise ValueError(f"{path.name}: duplicate record names")
    return tuple(vectors)


def golden_commands() -> tuple[GoldenVector, ...]:
    return load_golden("golden_commands.txt", protocol.FRAME_SIZE)


def golden_status() -> tuple[GoldenVector, ...]:
    return load_golden("golden_status.txt", protocol.STATUS_SIZE)


def pytest_generate_tests(metafunc: pytest.Metafunc) -> None:
    for fixture, vectors in (("command_vector", golden_commands), ("status_vector", golden_status)):
        if fixture in metafunc.fixturenames:
            loaded = vectors()
            metafunc.parametrize(fixture, loaded, ids=[v.name for v in loaded])


@pytest.fixture(scope="session")
def all_command_vectors() -> tuple[GoldenVector, ...]:
    return golden_commands()


@pytest.fixture(scope="session")
def all_status_vectors() -> tuple[GoldenVector, ...]:
    return golden_status()


@pytest.fixture(autouse=True)
def _own_calibration_store(tmp_path_factory, monkeypatch):
    """Each test (and every armctl it starts) keeps probed calibrations in its own data directory."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("armctl-data")))


# --- the real-time tests and Ctrl-C ------------------------------------------------------------


def pytest_sessionstart(session: pytest.Session) -> None:
    """Compile the package once, before the tests start armctl in fresh processes (hundreds of
    them): where PYTHONDONTWRITEBYTECODE is set (CI machines, containers), Python never writes its
    bytecode, and each fresh ``python -m armctl`` compiled every module it imports again — 0.3 s of
    CPU against 0.08 s with the bytecode there (``armctl lint`` of one line).  compileall writes it
    whatever that variable says; on the xdist controller only."""
    if hasattr(session.config, "workerinput"):
        _rewrite_my_share(session)
        return
    import compileall

    compileall.compile_dir(str(Path(armctl_package_dir())), quiet=1)


def _rewrite_my_share(session: pytest.Session) -> None:
    """Each xdist worker rewrites the asserts of its share of the test files (every Nth) and keeps
    them in pytest's cache, so that the other workers read them instead of rewriting them again.
    Rewriting every file costs 4.2 s of CPU, collecting with it done 1.7 s against 5.9 s; pytest
    writes no cache where PYTHONDONTWRITEBYTECODE is set (CI), so each of the 4 workers of the
    README's ``pytest -n 4`` rewrote all of them.  The cache entry carries its source's hash
    (pytest checks it): a changed file is rewritten.  This calls pytest's own rewriting, which is
    private: if it moves, the workers just rewrite as before."""
    config = session.config
    if config.getoption("assertmode") != "rewrite":
        return
    try:
        from _pytest.assertion import rewrite

        state = config.stash[rewrite.assertstate_key]
        number = int(config.workerinput["workerid"].removeprefix("gw"))
        files = sorted(path for arg in config.args for path in _test_files(Path(config.invocation_params.dir, arg)))
        for source in files[number::config.workerinput["workercount"]]:
            pyc = rewrite.get_cache_dir(source) / (source.name[:-3] + rewrite.PYC_TAIL)
            if rewrite._read_pyc(source, pyc) is None and rewrite.try_makedirs(pyc.parent):
                source_hash, code = rewrite._rewrite_test(source, config)
                rewrite._write_pyc(state, code, source_hash, pyc)
    except Exception:  # noqa: BLE001 - an optimisation only: collection rewrites what is missing
        return


def _test_files(path: Path) -> list[Path]:
    path = Path(str(path).split("::")[0])
    if path.is_dir():
        return list(path.rglob("test_*.py"))
    return [path] if path.name.startswith("test_") and path.suffix == ".py" else []


def armctl_package_dir() -> str:
    import armctl

    return os.path.dirname(armctl.__file__)


# The few tests that hold a worker for 5-70 s.  xdist's worksteal gives each worker a contiguous
# share of the collection, and an idle worker steals from the end of another's: a test starts a
# worker's run only at the head of its share, so these are put there.  The two that compute (the
# journal property's 2,000 examples, the bench read from two directories) head the even shares;
# those that mostly wait on a wall clock (a served arm's moves, a probe through a pty) are dealt
# out, longest first, over the odd shares: at most half the workers wait while the others keep the
# two cores busy.  (Sorted to the front of the list they all fell in the first share, and one
# worker ran them one after another: 137 s of its run, as long as the whole suite.)
LONG_COMPUTING = ("test_journal_property.py::test_a_resume_is_refused", "test_calibration_cli.py::test_bench_reads_no_configuration")
LONG_WAITING = (
    "test_probe_rates.py::test_installed_command_through_armctl_sim_pty_at_115200",
    "test_server_api.py::test_a_job_survives_a_crashed_server",
    "test_journal_wal.py::test_the_installed_command_resumes_after_ctrl_c", "test_review_faults.py::test_a_resume_",
    "test_review_users.py::test_sim_tcp_serves", "test_run_json_resume.py::test_kill_9_mid_job",
    "test_api_client.py::test_an_unprobed_arm_ends", "test_api.py::test_the_example_against_armctl_sim_pty",
    "test_crash_review.py::test_kill_9_twice", "test_probe_rates.py::test_installed_command_at_115200",
    "test_review6_realtime.py::test_a_second_ctrl_c_says", "test_review6_api.py::test_a_program_that_dies_of_an_exception",
    "test_review6_realtime.py::test_a_pty_set_to_another_rate", "test_review6_realtime.py::test_a_probe_of_the_last_sim_pty",
)


def _at_the_heads_of_the_shares(items: list[pytest.Item], workers: int) -> list[pytest.Item]:
    """``items`` with LONG_COMPUTING at the heads of the even shares and LONG_WAITING dealt over
    the odd ones (one worker: all of them first), the shares cut as worksteal cuts them."""
    def matching(patterns):
        return list(dict.fromkeys(item for pattern in patterns for item in items if pattern in item.nodeid))

    computing, waiting = matching(LONG_COMPUTING), matching(LONG_WAITING)
    heads: list[list[pytest.Item]] = [[] for _ in range(workers)]
    for long, shares in ((computing, range(0, workers, 2)), (waiting, range(1, workers, 2) or range(1))):
        for index, item in enumerate(long):
            heads[shares[index % len(shares)]].append(item)
    chosen = set(computing) | set(waiting)
    rest = iter([item for item in items if item not in chosen])
    ordered, remaining = [], len(items)
    for share, head in enumerate(heads):
        size = remaining // (workers - share)  # worksteal's first cut: the pending list over the idle workers
        remaining -= size
        ordered += head + [item for _, item in zip(range(size - len(head)), rest)]
    return ordered + list(rest)


@pytest.hookimpl(trylast=True)  # after -k and -m deselected: the shares are cut from what runs
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    workerinput = getattr(config, "workerinput", None)
    if workerinput is not None:  # every worker orders its collection the same way (xdist compares them)
        items[:] = _at_the_heads_of_the_shares(items, workerinput["workercount"])
    if not os.environ.get("ARMCTL_SKIP_REALTIME"):
        return
    skip = pytest.mark.skip(reason="ARMCTL_SKIP_REALTIME is set")
    for item in items:
        if item.get_closest_marker("realtime"):
            item.add_marker(skip)


@pytest.fixture
def ctrl_c():
    """``ctrl_c(after_s)`` sends this process a real SIGINT ``after_s`` seconds later.

    A runner started in the background, under nohup or by some CI inherits SIGINT *ignored*;
    then neither a signal nor ``_thread.interrupt_main`` raises KeyboardInterrupt and a test
    waiting for one waits for ever.  So the test runs with Python's own handler (KeyboardInterrupt
    in the main thread), and the previous handler is restored afterwards.  A timer that has not
    fired when the test ends is cancelled, so no stray Ctrl-C reaches a later test."""
    if threading.current_thread() is not threading.main_thread():
        pytest.fail("the ctrl_c fixture needs the main thread (signal handlers live there)")
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timers: list[threading.Timer] = []

    def press(after_s: float) -> None:
        timer = threading.Timer(after_s, os.kill, (os.getpid(), signal.SIGINT))
        timer.daemon = True
        timers.append(timer)
        timer.start()

    try:
        yield press
    finally:
        for timer in timers:
            timer.cancel()
            timer.join()
        signal.signal(signal.SIGINT, previous)


@pytest.fixture
def sim_pty():
    """``armctl sim --pty`` started as another process, in real time: yields its device path;
    afterwards Ctrl-C stops it, which must exit 130 (README: 130 Ctrl-C)."""
    import subprocess
    import sys

    simulator = subprocess.Popen(
        [sys.executable, "-m", "armctl", "sim", "--pty"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        ready = simulator.stdout.readline()
        path = re.fullmatch(r"simulated arm on (/dev/pts/\d+) \(Ctrl-C to stop\)\n", ready)
        assert path, ready
        yield path.group(1)
        simulator.send_signal(signal.SIGINT)
        assert simulator.wait(timeout=5) == 130
    finally:
        simulator.kill()
        simulator.communicate()
