"""docs/language.md is true: its examples are compiled and its transcripts re-run.

- every ```armctl block compiles with no diagnostic at all, read from a file the way
  ``armctl compile`` reads it, starting from nothing known;
- every ```armctl-error block has errors of exactly one code: the one its first ``;`` comment
  names (``--from-line N`` in that comment compiles it as ``armctl run --from-line N`` would);
- every transcript — a ```text block whose first line starts with ``$ `` — prints exactly what
  it shows: the script block right before it is saved as job.txt, then each ``$ armctl …``
  runs through click's CliRunner and ``$ printf '…' > FILE`` writes its bytes;
- together, the blocks use every statement and the transcripts show every code E001–E011.
"""

from __future__ import annotations

import re
import shlex
from pathlib import Path
from typing import NamedTuple, Optional

import pytest
from click.testing import CliRunner

from armctl.ui.cli import main
from armctl.script import RULES, compile_file

DOC = Path(__file__).resolve().parents[1] / "docs" / "language.md"
SCRIPT_KINDS = ("armctl", "armctl-error")


class Block(NamedTuple):
    kind: str  # the fence's info string, first word
    text: str  # the content, ending with a newline
    line: int  # 1-based line of the opening fence
    script: Optional["Block"]  # for a transcript: the script block right before it


def read_blocks() -> list[Block]:
    blocks: list[Block] = []
    lines = DOC.read_text(encoding="utf-8").split("\n")
    index = 0
    while index < len(lines):
        opening = re.match(r"```(\S*)", lines[index])
        if not opening:
            index += 1
            continue
        end = lines.index("```", index + 1)
        kind, text = opening.group(1), "".join(f"{line}\n" for line in lines[index + 1 : end])
        previous = blocks[-1] if blocks and blocks[-1].kind in SCRIPT_KINDS else None
        blocks.append(Block(kind, text, index + 1, previous if kind == "text" else None))
        index = end + 1
    return blocks


BLOCKS = read_blocks()
SCRIPTS = [b for b in BLOCKS if b.kind == "armctl"]
ERRORS = [b for b in BLOCKS if b.kind == "armctl-error"]
TRANSCRIPTS = [b for b in BLOCKS if b.kind == "text" and b.text.startswith("$ ")]


def ids(blocks: list[Block]) -> list[str]:
    return [f"language.md:{b.line}" for b in blocks]


def compile_block(block: Block, tmp_path: Path, from_line: int = 1):
    path = tmp_path / "job.txt"
    path.write_text(block.text, encoding="utf-8")
    compilation = compile_file(path, from_line=from_line)
    statements = list(compilation)
    return compilation, statements


@pytest.mark.parametrize("block", SCRIPTS, ids=ids(SCRIPTS))
def test_armctl_block_compiles(block: Block, tmp_path: Path) -> None:
    compilation, statements = compile_block(block, tmp_path)
    assert [d.render() for d in compilation.diagnostics] == []
    assert compilation.ok and statements


@pytest.mark.parametrize("block", ERRORS, ids=ids(ERRORS))
def test_armctl_error_block_fails_with_its_code(block: Block, tmp_path: Path) -> None:
    comment = re.search(r";([^\n]*)", block.text)
    assert comment, "an armctl-error block names its code in its first ; comment"
    code = re.search(r"\bE\d{3}\b", comment.group(1))
    assert code and code.group() in RULES, f"no known code in {comment.group()!r}"
    from_line = re.search(r"--from-line (\d+)", comment.group(1))
    compilation, _ = compile_block(block, tmp_path, int(from_line.group(1)) if from_line else 1)
    assert {d.code for d in compilation.diagnostics if d.is_error} == {code.group()}, \
        [d.render() for d in compilation.diagnostics]


def steps(transcript: Block) -> list[tuple[str, list[str]]]:
    """(command, the output lines it shows) for each ``$ `` line of a transcript."""
    result: list[tuple[str, list[str]]] = []
    for line in transcript.text.splitlines():
        if line.startswith("$ "):
            result.append((line[2:], []))
        else:
            result[-1][1].append(line.rstrip())
    return result


@pytest.mark.parametrize("transcript", TRANSCRIPTS, ids=ids(TRANSCRIPTS))
def test_transcript_shows_real_output(transcript: Block, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    if transcript.script is not None:
        (tmp_path / "job.txt").write_text(transcript.script.text, encoding="utf-8")
    for command, shown in steps(transcript):
        argv = shlex.split(command)
        if argv[0] == "printf":
            assert len(argv) == 4 and argv[2] == ">" and "%" not in argv[1], command
            data = argv[1].encode("latin-1").decode("unicode_escape").encode("latin-1")
            (tmp_path / argv[3]).write_bytes(data)
            output = ""
        else:
            assert argv[0] == "armctl", command
            output = CliRunner().invoke(main, argv[1:], catch_exceptions=False).output
        assert [line.rstrip() for line in output.splitlines()] == shown, f"$ {command}\n{output}"


def test_examples_cover_every_statement_and_every_code(tmp_path: Path) -> None:
    codes, keywords = set(), set()
    for block in SCRIPTS:
        codes |= {re.sub(r"^M\d+$", "M", s.code) for s in compile_block(block, tmp_path)[1]}
        keywords |= set(re.findall(r"^\s*(G9[01])\b", block.text, re.M))
    assert codes | keywords >= {
        "G1", "G220", "G222", "G230", "G6", "G300", "G301", "G4", "M", "G54", "RESET", "RESET CONNECTOR",
        "PAUSE", "POSE", "PROGRAM", "MODE", "G90", "G91",
    }
    shown = set(re.findall(r": (E\d{3}) ", "".join(t.text for t in TRANSCRIPTS)))
    assert shown == set(RULES)


@pytest.mark.parametrize("data", [b"G4 P1\nG4\x00 P1\n", b"G4 P1 ;" + b"x" * 4993 + b"\n"], ids=["nul", "long"])
def test_e011_messages_quoted_in_prose_are_the_compilers(data: bytes, tmp_path: Path) -> None:
    path = tmp_path / "job.txt"
    path.write_bytes(data)
    [diagnostic] = compile_file(path).finish()
    assert diagnostic.code == "E011" and f"`{diagnostic.message}`" in DOC.read_text(encoding="utf-8")
