"""A text progress bar drawn on rank 0 only (for the CLI and demos, not the library)."""

from __future__ import annotations

import sys
import time

from mpi4py import MPI

__all__ = ["ProgressBar"]


class ProgressBar:
    """``bar.update(fraction, text)`` redraws a one-line bar on stderr of rank 0.

    Redraws at most every ``min_interval`` seconds; quiet when stderr is not a terminal
    unless ``force``; ``close()`` ends the line.
    """

    def __init__(self, label: str = "", width: int = 30, comm: MPI.Comm = MPI.COMM_WORLD,
                 min_interval: float = 0.2, force: bool = False, stream=None):
        self.label = label
        self.width = width
        self.stream = stream or sys.stderr
        self.active = comm.rank == 0 and (force or self.stream.isatty())
        self.min_interval = min_interval
        self._last = 0.0
        self._t0 = time.perf_counter()

    def update(self, fraction: float, text: str = "") -> None:
        if not self.active:
            return
        now = time.perf_counter()
        if now - self._last < self.min_interval and fraction < 1.0:
            return
        self._last = now
        f = min(max(fraction, 0.0), 1.0)
        n = int(round(f * self.width))
        bar = "#" * n + "-" * (self.width - n)
        self.stream.write(f"\r{self.label} [{bar}] {100 * f:5.1f}% {now - self._t0:6.1f}s {text}")
        self.stream.flush()

    def close(self) -> None:
        if self.active:
            self.update(1.0)
            self.stream.write("\n")
            self.stream.flush()
