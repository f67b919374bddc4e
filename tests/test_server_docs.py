"""Every HTTP example of docs/server.md, run in order against the installed ``armctl serve``
with the two arms the page names: each answer has the status and the keys shown, and the
values that do not change from run to run (outcomes, codes, lint findings, …) as shown."""
from __future__ import annotations

import json
import re
from dataclasses import fields
from pathlib import Path

import pytest

pytest.importorskip("aiohttp", reason="the serve extra (aiohttp) is not installed: pip install -e '.[serve]'")

from serve_process import served  # noqa: E402

from armctl.host.api import RunResult  # noqa: E402

pytestmark = [pytest.mark.realtime, pytest.mark.timeout(120)]

DOC = Path(__file__).parent.parent / "docs" / "server.md"
BLOCK = re.compile(r"```(http|json)\n(.*?)```", re.S)
RESULT_WORDS = {f.name for f in fields(RunResult)}
STABLE = {"outcome", "code", "line", "column", "end_column", "severity", "errors", "feed_percent", "toggle_sent",
          "stopping", "name", "port", "file", "message", "kind", "first_line", "running", "omitted", "start", "points"}


def examples() -> list[tuple[str, str]]:
    section = DOC.read_text().split("### The HTTP API", 1)[1].split("### The WebSocket", 1)[0]
    blocks = BLOCK.findall(section)
    pairs = []
    for (kind, request), (answer_kind, answer) in zip(blocks[::2], blocks[1::2]):
        assert (kind, answer_kind) == ("http", "json"), (request, answer)
        pairs.append((request, answer))
    return pairs


def parse_request(text: str) -> tuple[str, str, dict, str | None]:
    head, _, body = text.partition("\n\n")
    lines = head.strip("\n").split("\n")
    method, path = lines[0].split(" ", 1)
    headers = dict(line.split(": ", 1) for line in lines[1:])
    return method, path, headers, body if body else None


def same_shape(documented, answered, where: str) -> None:
    assert type(documented) is type(answered) or {type(documented), type(answered)} <= {int, float}, (where, answered)
    if isinstance(documented, dict):
        # every key shown is answered; an answer may carry more only where it is a RunResult's
        # word the page's example predates (the result is documented in docs/api.md, field by field)
        assert set(documented) <= set(answered), (where, sorted(set(documented) - set(answered)))
        assert set(answered) - set(documented) <= RESULT_WORDS, (where, sorted(set(answered) - set(documented)))
        for key, value in documented.items():
            if key in STABLE:
                assert answered[key] == value, (where, key, answered[key])
            same_shape(value, answered[key], f"{where}.{key}") if value is not None and answered[key] is not None else None
    elif isinstance(documented, list) and documented and not isinstance(documented[0], (int, float)):
        assert len(documented) == len(answered), (where, answered)
        for index, (one, other) in enumerate(zip(documented, answered)):
            same_shape(one, other, f"{where}[{index}]")


def test_every_http_example_of_docs_server_md(tmp_path):
    pairs = examples()
    assert len(pairs) >= 15
    job_id = None
    with served("--arm", "a=sim://?speed=20", "--arm", "b=sim://?speed=20", journal=tmp_path) as server:
        for request, answer in pairs:
            method, path, headers, body = parse_request(request)
            path = path.replace("{id}", job_id or "")
            status_line, _, documented_text = answer.partition("\n")
            documented = json.loads(documented_text)
            if method == "GET" and re.fullmatch(r"/api/arms/\w+/jobs/[\w-]+", path) and documented.get("outcome"):
                arm = path.split("/")[3]
                server.wait_job(arm, job_id)  # the example shows the job ended
            status, answered = server.request(method, path, body, headers)
            assert status == int(status_line), (request, answered)
            same_shape(documented, answered, f"{method} {path}")
            if status == 201:
                job_id = answered["id"]
