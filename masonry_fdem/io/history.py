"""History CSV: one row per output time (time, loads, monitored displacements, energies)."""

from __future__ import annotations

import csv
from collections.abc import Mapping
from pathlib import Path

from mpi4py import MPI

import numpy as np

__all__ = ["History"]


class History:
    """Rows of scalars, written to CSV on rank 0 as they arrive (flushed each row).

    Every rank calls :meth:`append` with the same (already reduced) values; only rank 0
    writes. Columns are fixed by the first row. Rows are also kept in memory
    (:meth:`column`).

    Args:
        path: CSV file to write (parent folders are created), or None for memory only.
        comm: communicator; rank 0 writes.
    """

    def __init__(self, path: str | Path | None, comm: MPI.Comm = MPI.COMM_WORLD):
        self.path = Path(path) if path is not None else None
        self.comm = comm
        self.columns: list[str] | None = None
        self.rows: list[list[float]] = []
        self._file = None
        self._writer = None

    def append(self, values: Mapping[str, float]) -> None:
        """Add a row; vector values (e.g. a monitored (ux, uy)) become name_x, name_y."""
        flat: dict[str, float] = {}
        for key, val in values.items():
            arr = np.atleast_1d(np.asarray(val, dtype=float))
            if arr.size == 1:
                flat[key] = float(arr[0])
            else:
                for suffix, x in zip("xyz", arr, strict=False):
                    flat[f"{key}_{suffix}"] = float(x)
        if self.columns is None:
            self.columns = list(flat)
            if self.path is not None and self.comm.rank == 0:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._file = open(self.path, "w", newline="")  # noqa: SIM115
                self._writer = csv.writer(self._file)
                self._writer.writerow(self.columns)
        elif list(flat) != self.columns:
            raise ValueError(f"history columns changed: {list(flat)} vs {self.columns}")
        row = [flat[c] for c in self.columns]
        self.rows.append(row)
        if self._writer is not None:
            self._writer.writerow([f"{x:.12g}" for x in row])
            self._file.flush()

    def column(self, name: str) -> np.ndarray:
        """All values of one column."""
        if self.columns is None or name not in self.columns:
            raise KeyError(f"no history column {name!r}")
        j = self.columns.index(name)
        return np.array([r[j] for r in self.rows])

    def close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None
            self._writer = None

    def __enter__(self) -> History:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
