"""Repeat blocks, above the grammar: ``O<label> repeat [n]`` … ``O<label> endrepeat``.

Strategy: the grammar sees each O-line alone; this module pairs them.  While a repeat block is
open, the compiler hands every parsed line to ``BlockCollector.add`` instead of executing it,
so only the body of the outermost open block is held in memory (as parsed lines, each parsed
once), never the file.  Nested blocks become ``Block`` items inside their parent's body.
``close`` returns the outermost block once it is complete; the compiler then runs it
(evaluating each count when the block starts, so parameters assigned inside a body advance
from one iteration to the next).

Structure problems are returned as ``Problem`` records (E008) and recovered from the way a
reader would expect: an endrepeat whose label is open further out closes the blocks inside
it (each reported unclosed); an endrepeat with no open block of its label is reported and
ignored; blocks still open at the end of the file are reported and closed there.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple, Optional, Union

from .nodes import BlockLine, Node


class Line(NamedTuple):
    """One parsed source line held in a block body."""

    number: int
    text: str
    node: Node


@dataclass(slots=True)
class Block:
    """An ``O<label> repeat`` block: its opening line, its body, and where it ended."""

    label: str
    opening: Line
    items: list[Union[Line, "Block"]] = field(default_factory=list)
    end_line: Optional[int] = None

    @property
    def line(self) -> int:
        return self.opening.number

    @property
    def count(self):
        return self.opening.node.count


class Problem(NamedTuple):
    """A structure error to report (always E008): on which line, where, what, and a hint."""

    line: Line
    column: int
    end_column: int
    message: str
    hint: Optional[str] = None


class BlockCollector:
    """Pairs repeat/endrepeat lines and buffers the body of the outermost open block."""

    def __init__(self) -> None:
        self.stack: list[Block] = []  # the open blocks, outermost first; non-empty = collecting

    @property
    def collecting(self) -> bool:
        """True while a block is open: lines belong to its body."""
        return bool(self.stack)

    def add(self, line: Line) -> None:
        self.stack[-1].items.append(line)

    def open(self, line: Line, problems: list[Problem]) -> None:
        node: BlockLine = line.node
        for block in self.stack:
            if block.label == node.label:
                problems.append(Problem(
                    line, node.column, node.column + len(node.label),
                    f"{node.label} is already open (line {block.line})",
                    "give each nested block its own label",
                ))
                break
        block = Block(node.label, line)
        if self.stack:
            self.stack[-1].items.append(block)
        self.stack.append(block)

    def close(self, line: Line, problems: list[Problem]) -> Optional[Block]:
        """Close the block ``line`` ends; return the outermost block if it is now complete."""
        node: BlockLine = line.node
        if node.count is not None:
            problems.append(Problem(line, *node.count_span, f"{node.label} endrepeat takes no count",
                                    f"the count goes on the repeat line: {node.label} repeat [n]"))
        labels = [block.label for block in self.stack]
        if node.label not in labels:
            problems.append(Problem(
                line, node.column, node.end_column, f"{node.label} endrepeat has no {node.label} repeat before it",
                f"open blocks: {', '.join(labels)}" if labels else None,
            ))
            return None
        while True:
            block = self.stack.pop()
            block.end_line = line.number
            if block.label == node.label:
                break
            problems.append(Problem(
                block.opening, block.opening.node.column, block.opening.node.end_column,
                f"{block.label} repeat is not closed before {node.label} endrepeat (line {line.number})",
                f"add {block.label} endrepeat inside it",
            ))
        return None if self.stack else block

    def close_all(self, last_line: int, problems: list[Problem]) -> Optional[Block]:
        """At the end of the file: report every open block and return the outermost one."""
        outermost = self.stack[0] if self.stack else None
        for block in self.stack:
            block.end_line = last_line
            problems.append(Problem(
                block.opening, block.opening.node.column, block.opening.node.end_column,
                f"{block.label} repeat is never closed", f"add {block.label} endrepeat after its body",
            ))
        self.stack.clear()
        return outermost
