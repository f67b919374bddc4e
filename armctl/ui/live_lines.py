"""A panel kept in place on a terminal, rewriting only the lines that changed.

Strategy: rich's ``Live`` draws its renderable whole at every refresh, and refreshes on a thread
of its own whether or not anything changed: ``armctl run``'s panel (some 3.4 KB at 120 × 40, its
map included) cost 1.2 MB of terminal output for a 16 s job, 347 whole panels.  Here the caller
draws when it has something new (``draw``): the renderable is rendered to lines with the
console's own colours and width (``Console.capture``), compared with the lines on the screen, and
only those that differ are written — the cursor moved over the panel with the controls rich's
``Live`` uses (CR, LF, erase line, cursor up), and left below the panel in between.  A panel of
another height, or a terminal of another size, is drawn whole; lines past the terminal's height
are cut (the cursor cannot go up past the top of the screen).  ``print_above`` prints a message
above the panel and draws the panel again below it.  Draws may come from any thread (a lock).
"""

from __future__ import annotations

import threading

ERASE_LINE = "\r\x1b[2K"


def _up(rows: int) -> str:
    return f"\x1b[{rows}A" if rows else ""


class LiveLines:
    """The panel on ``console`` (a rich ``Console`` on a terminal); the cursor hidden meanwhile."""

    def __init__(self, console) -> None:
        self.console = console
        self._shown: list[str] = []  # the panel's lines on the screen, the cursor on the row below
        self._size = None  # the terminal's size they were drawn for
        self._lock = threading.RLock()

    def __enter__(self) -> "LiveLines":
        self.console.show_cursor(False)
        return self

    def __exit__(self, *exc) -> None:
        self.console.show_cursor(True)

    def draw(self, renderable) -> None:
        """Show ``renderable`` in the panel's place, writing only the lines that changed."""
        with self._lock:
            lines, shown = self._lines(renderable), self._shown
            size = self.console.size
            if len(lines) != len(shown) or size != self._size:
                text = self._whole(lines)
            else:
                changed = [row for row, (old, new) in enumerate(zip(shown, lines)) if old != new]
                if not changed:
                    return
                first = changed[0]
                text = _up(len(shown) - first) + "".join(
                    ERASE_LINE + new + "\n" if new != old else "\n" for old, new in zip(shown[first:], lines[first:]))
            self._shown, self._size = lines, size
            self._write(text)

    def print_above(self, renderable) -> None:
        """Print ``renderable`` (a message: soft-wrapped, the terminal wraps it) where the panel
        begins, and the panel again below it.  The panel's rows are erased first, as rich's
        ``Live`` does: a message the terminal wraps covers rows no line of it erases."""
        with self._lock:
            with self.console.capture() as capture:
                self.console.print(renderable, soft_wrap=True)
            shown, self._shown = self._shown, []
            self._write(ERASE_LINE + "\x1b[1A\x1b[2K" * len(shown) + capture.get() + self._whole(shown))
            self._shown = shown

    def _whole(self, lines: list[str]) -> str:
        """Every line of ``lines`` over the panel on the screen; the rows it no longer covers erased."""
        shown = self._shown
        text = _up(len(shown)) + "".join(ERASE_LINE + line + "\n" for line in lines)
        left = len(shown) - len(lines)
        return text + (ERASE_LINE + "\n") * left + _up(left) if left > 0 else text

    def _lines(self, renderable) -> list[str]:
        console = self.console
        with console.capture() as capture:
            console.print(renderable)
        return capture.get().split("\n")[:-1][: max(1, console.size.height - 1)]

    def _write(self, text: str) -> None:
        file = self.console.file
        file.write(text)
        file.flush()
