"""A dependency-free progress bar for long command-line runs.

The bar is redrawn in place on standard error, and only when standard error is a terminal and the
caller did not ask for quiet output: logs and pipes never fill with carriage returns. Whatever the
mode, :meth:`Progress.close` writes one final line (what was done and how long it took), so a log
still records the run.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

__all__ = ["Progress"]


def _format_seconds(seconds: float) -> str:
    seconds = max(0.0, seconds)
    if seconds < 60:
        return f"{seconds:.1f} s"
    minutes, rest = divmod(int(round(seconds)), 60)
    return f"{minutes} min {rest:02d} s"


class Progress:
    """Counts ``total`` units of work and draws ``label [#####.....] done/total eta``.

    Parameters
    ----------
    total:
        Units of work expected (at least 1 is assumed).
    label:
        Printed before the bar and in the final line.
    enabled:
        Draw the bar. ``None`` (default) draws it only when ``stream`` is a terminal.
    stream:
        Where to write; default ``sys.stderr``.
    width:
        Characters of the bar itself.
    """

    def __init__(
        self,
        total: int,
        label: str = "",
        *,
        enabled: bool | None = None,
        stream: TextIO | None = None,
        width: int = 30,
    ) -> None:
        self.total = max(1, int(total))
        self.label = label
        self.stream = stream if stream is not None else sys.stderr
        if enabled is None:
            isatty = getattr(self.stream, "isatty", None)
            enabled = bool(isatty and isatty())
        self.enabled = enabled
        self.width = width
        self.done = 0
        self.note = ""
        self.started = time.perf_counter()
        self._last_draw = 0.0
        self._closed = False

    @property
    def elapsed(self) -> float:
        """Seconds since the bar was created."""
        return time.perf_counter() - self.started

    def update(self, n: int = 1, note: str | None = None) -> None:
        """Marks ``n`` more units done; ``note`` (e.g. the current table) is shown after the bar."""
        self.done = min(self.total, self.done + n)
        if note is not None:
            self.note = note
        if not self.enabled:
            return
        now = time.perf_counter()
        # Redraw at most ~20 times a second, but always draw the last unit.
        if self.done < self.total and now - self._last_draw < 0.05:
            return
        self._last_draw = now
        self._draw()

    def set_note(self, note: str) -> None:
        """Changes the note (e.g. the current table) shown after the bar from the next redraw on."""
        self.note = note

    def _draw(self) -> None:
        fraction = self.done / self.total
        filled = int(round(fraction * self.width))
        bar = "#" * filled + "." * (self.width - filled)
        eta = ""
        if 0 < self.done < self.total:
            eta = f" eta {_format_seconds(self.elapsed * (self.total - self.done) / self.done)}"
        line = f"{self.label} [{bar}] {self.done}/{self.total}{eta} {self.note}".rstrip()
        columns = 100
        self.stream.write("\r" + line[:columns].ljust(columns))
        self.stream.flush()

    def close(self, message: str | None = None) -> None:
        """Ends the bar and writes the final line (``message`` or a default), bar or no bar."""
        if self._closed:
            return
        self._closed = True
        if self.enabled:
            self.stream.write("\r" + " " * 100 + "\r")
        if message is None:
            message = f"{self.label}: {self.done}/{self.total} done in {_format_seconds(self.elapsed)}"
        self.stream.write(message + "\n")
        self.stream.flush()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
