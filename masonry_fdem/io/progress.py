"""Progress output of rank 0 (for the CLI and demos, not the library): a tqdm bar on a
terminal, or one plain line per increment for logs and pipes."""

from __future__ import annotations

import sys

from mpi4py import MPI

from tqdm import tqdm

__all__ = ["ProgressBar"]


class ProgressBar:
    """Progress of a run, drawn by rank 0 only (every other rank is silent).

    Two ways to report:

    * ``bar.update(fraction, text)``: the fraction done (0 to 1) of a run whose end is
      known (a time span, a load factor), ``text`` after the bar;
    * ``bar.increment(line, **postfix)``: one more increment of a run whose number of
      increments is not known beforehand; the bar counts increments and shows
      ``postfix`` (say ``load="4.00 kN", u="1.234 mm"``) after the count.

    Args:
        label: the name before the bar.
        comm: MPI communicator (rank 0 draws).
        mode: ``"bar"``: a tqdm bar on ``stream`` (stderr by default), only when it is a
            terminal unless ``force``; ``"lines"``: :meth:`increment` prints ``line`` as
            one line on ``stream`` (stdout by default), :meth:`update` prints nothing.
        unit: the name of one increment on the bar.
        force: draw the bar even when the stream is not a terminal.
        stream: where to write.
        min_interval: the shortest time between two redraws of the bar [s].
    """

    def __init__(self, label: str = "", width: int | None = None,
                 comm: MPI.Comm = MPI.COMM_WORLD, min_interval: float = 0.2,
                 force: bool = False, stream=None, mode: str = "bar",
                 unit: str = "increment"):
        if mode not in ("bar", "lines"):
            raise ValueError(f"progress mode {mode!r}: expected 'bar' or 'lines'")
        self.label = label
        self.mode = mode
        self.unit = unit
        self.stream = stream or (sys.stdout if mode == "lines" else sys.stderr)
        rank0 = comm.rank == 0
        if mode == "lines":
            self.active = rank0
        else:
            self.active = rank0 and (force or _isatty(self.stream))
        self.width = width
        self.min_interval = min_interval
        self._bar: tqdm | None = None
        self._kind: str | None = None  # "fraction" or "count", fixed by the first call
        self.count = 0

    def _open(self, kind: str) -> tqdm:
        if self._bar is None:
            self._kind = kind
            common = dict(desc=self.label or None, file=self.stream, ncols=self.width,
                          mininterval=self.min_interval, leave=True, dynamic_ncols=False)
            if kind == "fraction":
                self._bar = tqdm(total=100.0, unit="%",
                                 bar_format="{desc}: {percentage:5.1f}%|{bar}| "
                                            "[{elapsed}<{remaining}] {postfix}", **common)
            else:
                self._bar = tqdm(total=None, unit=f" {self.unit}s", **common)
        return self._bar

    def update(self, fraction: float, text: str = "") -> None:
        """The run is ``fraction`` (0 to 1) done; ``text`` after the bar."""
        if not self.active or self.mode != "bar":
            return
        bar = self._open("fraction")
        f = 100.0 * min(max(float(fraction), 0.0), 1.0)
        if text:
            bar.set_postfix_str(text, refresh=False)
        bar.update(f - bar.n)

    def increment(self, line: str = "", **postfix) -> None:
        """One more increment: a line of its own (mode ``"lines"``) or the bar's count
        and ``postfix`` (mode ``"bar"``)."""
        self.count += 1
        if not self.active:
            return
        if self.mode == "lines":
            print(line, file=self.stream, flush=True)
            return
        bar = self._open("count")
        if postfix:
            bar.set_postfix(postfix, refresh=False)
        bar.update(1)

    def close(self) -> None:
        """End the bar (a full bar for a run that reported fractions)."""
        if self._bar is not None:
            if self._kind == "fraction":
                self._bar.update(100.0 - self._bar.n)
            self._bar.close()
            self._bar = None

    def __enter__(self) -> ProgressBar:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False
