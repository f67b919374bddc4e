"""The Lark parser's tables are cached in the user's cache folder; no state of that cache can
break a run (issue 13, start-up).  Each case runs the installed command in a fresh process."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SCRIPT = "#<x> = 150\nG1 X[#<x> + 50] Y0 Z150 A180 B0 C0 F3000 S1000\nG1 X[#<x> * 4] Y[1 - 1] Z150\n"  # X600: L103


def _lint(tmp_path: Path, cache_home) -> subprocess.CompletedProcess:
    script = tmp_path / "job.txt"
    script.write_text(SCRIPT, encoding="utf-8")
    env = {**os.environ, "XDG_CACHE_HOME": str(cache_home)}
    return subprocess.run([sys.executable, "-m", "armctl", "lint", "--format", "json", script.name],
                          capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)


def _cache_files(cache_home: Path) -> list[Path]:
    return sorted((cache_home / "armctl").glob("grammar-*.cache"))


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """What lint says with a cache that works (built by the first run, read by the second); the
    same for every test (module scope: two processes once, not for each test)."""
    tmp = tmp_path_factory.mktemp("reference")
    first, second = _lint(tmp, tmp / "cache"), _lint(tmp, tmp / "cache")
    assert first.returncode == second.returncode == 0, first.stderr
    assert "L103" in first.stdout and "Traceback" not in first.stderr
    assert first.stdout == second.stdout
    assert len(_cache_files(tmp / "cache")) == 1
    return first


def test_the_first_run_builds_the_cache_and_the_next_reads_it(tmp_path, reference):
    done = _lint(tmp_path, tmp_path / "cache")
    assert (done.returncode, done.stdout, done.stderr) == (reference.returncode, reference.stdout, reference.stderr)
    (cached,) = _cache_files(tmp_path / "cache")
    before = cached.stat().st_mtime_ns
    again = _lint(tmp_path, tmp_path / "cache")
    assert again.stdout == reference.stdout
    assert cached.stat().st_mtime_ns == before  # read, not rewritten


@pytest.mark.parametrize("content", [b"", b"garbage\n", b"0" * 64 + b"\n\x80\x04junk"], ids=["empty", "garbage", "stale"])
def test_a_corrupt_or_stale_cache_is_rebuilt(tmp_path, reference, content):
    _lint(tmp_path, tmp_path / "cache")
    (cached,) = _cache_files(tmp_path / "cache")
    cached.write_bytes(content)
    done = _lint(tmp_path, tmp_path / "cache")
    assert (done.returncode, done.stdout, done.stderr) == (reference.returncode, reference.stdout, reference.stderr)
    assert cached.read_bytes() != content  # rebuilt and written again


def test_an_unusable_cache_folder_is_no_cache(tmp_path, reference):
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder would be", encoding="utf-8")
    done = _lint(tmp_path, blocker)
    assert (done.returncode, done.stdout, done.stderr) == (reference.returncode, reference.stdout, reference.stderr)


def test_a_cache_file_that_is_a_folder_or_unwritable_is_ignored(tmp_path, reference):
    _lint(tmp_path, tmp_path / "cache")
    (cached,) = _cache_files(tmp_path / "cache")
    cached.unlink()
    cached.mkdir()  # neither readable nor writable as a file
    done = _lint(tmp_path, tmp_path / "cache")
    assert (done.returncode, done.stdout, done.stderr) == (reference.returncode, reference.stdout, reference.stderr)
    assert cached.is_dir()
