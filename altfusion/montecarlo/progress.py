"""A one-line progress display on stderr: runs done, rate, time left, failures."""

import sys
import time
from typing import TextIO

BAR_WIDTH = 24


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    if seconds >= 3600:
        return f"{seconds // 3600}h{seconds % 3600 // 60:02d}m"
    return f"{seconds // 60}m{seconds % 60:02d}s" if seconds >= 60 else f"{seconds}s"


class Progress:
    """Counts finished runs of ``total`` (``done`` of them finished before this session).

    On a terminal the line is redrawn in place (at most every 0.2 s); otherwise a line is
    printed at each tenth of the work, so logs stay short.
    """

    def __init__(self, total: int, done: int = 0, label: str = "runs",
                 stream: TextIO | None = None, enabled: bool = True):
        self.total, self.done, self.failed, self.label = total, done, 0, label
        self._initial = done
        self._stream = stream or sys.stderr
        self._enabled = enabled
        self._tty = self._stream.isatty()
        self._start = time.monotonic()
        self._last_draw = 0.0
        self._last_tenth = -1
        self._draw(final=True)

    def advance(self, failed: bool = False) -> None:
        self.done += 1
        self.failed += failed
        self._draw()

    def line(self) -> str:
        fraction = self.done / self.total if self.total else 1.0
        filled = int(round(BAR_WIDTH * fraction))
        elapsed = time.monotonic() - self._start
        new = self.done - self._initial
        text = (f"[{'#' * filled}{'.' * (BAR_WIDTH - filled)}] {self.done}/{self.total} "
                f"{self.label}")
        if new and elapsed > 0:
            rate = new / elapsed
            text += f"  {60 * rate:.1f}/min  {_duration(elapsed)} elapsed"
            if self.done < self.total:
                text += f", ~{_duration((self.total - self.done) / rate)} left"
        if self.failed:
            text += f"  ({self.failed} failed)"
        return text

    def _draw(self, final: bool = False) -> None:
        if not self._enabled:
            return
        now = time.monotonic()
        if self._tty:
            if final or now - self._last_draw >= 0.2 or self.done == self.total:
                self._stream.write("\r" + self.line() + "\x1b[K")
                self._stream.flush()
                self._last_draw = now
            return
        tenth = int(10 * self.done / self.total) if self.total else 10
        if tenth != self._last_tenth or final:
            self._stream.write(self.line() + "\n")
            self._stream.flush()
            self._last_tenth = tenth

    def close(self) -> None:
        """Draw the final state and end the line."""
        if not self._enabled:
            return
        if self._tty:
            self._draw(final=True)
            self._stream.write("\n")
            self._stream.flush()
        elif self._last_tenth != 10:
            self._draw(final=True)
