"""Every python code block of docs/api.md (and the README's) runs, as written, in a fresh process.

The page says how: ``ARMCTL_PORT=sim://?clock=virtual`` (model time moves only while armctl
waits, so each block takes a fraction of a second) and a ``job.txt`` — the five-frame
tests/data/scripts_cli/short_job.txt — in the working directory.  A block that raises fails
its test, so the page cannot rot.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PAGE = ROOT / "docs" / "api.md"
JOB = ROOT / "tests" / "data" / "scripts_cli" / "short_job.txt"
_BLOCK = re.compile(r"^```python\n(.*?)^```$", re.M | re.S)


def python_blocks(page: Path = PAGE) -> list[tuple[int, str]]:
    text = page.read_text(encoding="utf-8")
    return [(text.count("\n", 0, match.start()) + 1, match.group(1)) for match in _BLOCK.finditer(text)]


def test_the_page_has_examples_and_the_readme_links_it():
    assert len(python_blocks()) >= 5
    assert "(docs/api.md)" in (ROOT / "README.md").read_text(encoding="utf-8")


README = ROOT / "README.md"
BLOCKS = [(PAGE, *block) for block in python_blocks()] + [(README, *block) for block in python_blocks(README)]


@pytest.mark.parametrize("page, line, code", BLOCKS, ids=[f"{page.name}:{line}" for page, line, _code in BLOCKS])
def test_a_python_block_of_docs_api_md_runs(tmp_path, page, line, code):
    if page == README:  # as a newcomer runs it in a fresh clone: the repository's scripts/, no job.txt
        shutil.copytree(ROOT / "scripts", tmp_path / "scripts")
    else:
        shutil.copy(JOB, tmp_path / "job.txt")
    env = {**os.environ, "ARMCTL_PORT": "sim://?clock=virtual"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, env=env, cwd=tmp_path)
    assert done.returncode == 0, f"line {line}:\n{done.stderr}"
    assert "Traceback" not in done.stderr
