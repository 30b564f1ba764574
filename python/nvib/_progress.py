"""A one-line text progress bar for long runs: ``[#####.....] 45%  ETA 3.2 s``.

Pass an instance as ``solve(..., progress=bar)``; the integrator calls it
every 0.1 s or so with (step, n_steps). Nothing is drawn until the run is
expected to last longer than ``min_duration`` seconds, so short runs stay silent.
"""

from __future__ import annotations

import math
import sys
import time


def format_duration(seconds: float) -> str:
    """3.2 s, 1 min 05 s, 2 h 03 min."""
    if not math.isfinite(seconds):
        return "?"
    seconds = max(seconds, 0.0)
    if seconds < 59.95:
        return f"{seconds:.1f} s"
    if seconds < 3600:
        m, s = divmod(int(round(seconds)), 60)
        return f"{m} min {s:02d} s"
    h, m = divmod(int(round(seconds / 60)), 60)
    return f"{h} h {m:02d} min"


class ProgressBar:
    """Draws ``[#####.....] 45%  ETA 3.2 s`` on ``stream`` (stderr by default), rewriting one line.

    ``bar(step, n)`` updates it; ``close()`` finishes the line (drawing 100 %
    if the last update reached the end, or ``done=True`` is passed). With
    ``enabled=False`` it never writes. The clock starts at construction
    (or at ``start()``).
    """

    def __init__(self, stream=None, *, enabled: bool = True, min_duration: float = 1.0, width: int = 30,
                 clock=time.perf_counter):
        self.stream = sys.stderr if stream is None else stream
        self.enabled = bool(enabled)
        self.min_duration = float(min_duration)
        self.width = int(width)
        self._clock = clock
        self._start = clock()
        self._drawn = False
        self._closed = False
        self._last_len = 0
        self._frac = 0.0

    def start(self) -> None:
        """Restart the clock (call just before the run when the bar was made earlier)."""
        self._start = self._clock()

    @property
    def drawn(self) -> bool:
        """True once the bar has been shown."""
        return self._drawn

    def __call__(self, step: int, n: int) -> None:
        if not self.enabled or self._closed or n <= 0:
            return
        frac = min(max(step / n, 0.0), 1.0)
        self._frac = frac
        elapsed = self._clock() - self._start
        eta = elapsed * (1.0 - frac) / frac if frac > 0 else math.inf
        if not self._drawn and elapsed + eta < self.min_duration:
            return
        self._write(self._line(frac, f"ETA {format_duration(eta)}"))

    def close(self, done: bool | None = None) -> None:
        """End the line. ``done=True`` draws the full bar with the elapsed time;
        ``done=False`` leaves the bar where the run stopped."""
        if self._closed:
            return
        self._closed = True
        if not self._drawn:
            return
        if done is None:
            done = self._frac >= 1.0
        elapsed = self._clock() - self._start
        if done:
            self._write(self._line(1.0, f"in {format_duration(elapsed)}"))
        else:
            self._write(self._line(self._frac, f"stopped after {format_duration(elapsed)}"))
        self._write_raw("\n")

    def __enter__(self) -> "ProgressBar":
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(done=None if exc_type is None else False)

    def _line(self, frac: float, tail: str) -> str:
        filled = min(self.width, int(frac * self.width))
        return f"[{'#' * filled}{'.' * (self.width - filled)}] {int(100 * frac):3d}%  {tail}"

    def _write(self, text: str) -> None:
        pad = " " * max(0, self._last_len - len(text))
        self._last_len = len(text)
        self._drawn = True
        self._write_raw("\r" + text + pad)

    def _write_raw(self, text: str) -> None:
        try:
            self.stream.write(text)
            self.stream.flush()
        except (OSError, ValueError):  # closed or broken stream: stop drawing, never abort the run
            self.enabled = False
