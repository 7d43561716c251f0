"""A one-line progress display, ``done/total`` (no tqdm): rewritten in place on a terminal,
printed at most every ``interval`` seconds (and at the end) otherwise, so logs of long batches
stay short."""

from __future__ import annotations

import sys
import time
from typing import IO, Optional


class ProgressLine:
    def __init__(self, total: int, stream: Optional[IO[str]] = None, interval: float = 5.0,
                 label: str = "tessd.batch"):
        self.total = total
        self.stream = stream if stream is not None else sys.stderr
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = 0.1 if self.tty else interval
        self.label = label
        self.start = time.monotonic()
        self._last = -1e9
        self.done = 0
        self.errors = 0

    def text(self) -> str:
        elapsed = time.monotonic() - self.start
        pct = 100.0 * self.done / self.total if self.total else 100.0
        rate = self.done / elapsed * 60.0 if elapsed > 0 else 0.0
        return ("%s: %d/%d assets (%.0f%%), %d with errors, %.1fs, %.0f assets/min"
                % (self.label, self.done, self.total, pct, self.errors, elapsed, rate))

    def update(self, done: int, errors: int = 0, force: bool = False) -> None:
        self.done, self.errors = done, errors
        now = time.monotonic()
        if not force and done < self.total and now - self._last < self.interval:
            return
        self._last = now
        if self.tty:
            self.stream.write("\r\x1b[K" + self.text())
            if done >= self.total:
                self.stream.write("\n")
        else:
            self.stream.write(self.text() + "\n")
        self.stream.flush()


__all__ = ["ProgressLine"]
