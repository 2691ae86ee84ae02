"""Checkpoints of a run and a clean stop on Ctrl-C / SIGTERM.

A checkpoint is one folder per generation under ``RUN_DIR/checkpoint/``::

    checkpoint/
        CURRENT             the name of the complete generation ("g000012")
        g000012/
            rank0.pkl       this rank's state (one file per rank)
            rank1.pkl
            manifest.json   rank 0, last: version, ranks, step, kind, case hash, the
                            files' SHA-256

A generation is written in this order: every rank writes its file to ``rank{r}.pkl.tmp``,
flushes it to disk and renames it into place; after a barrier rank 0 writes the manifest
the same way, then replaces ``CURRENT`` (a new file renamed over the old one) and only
then removes the generations before the previous one. A process killed at any point
leaves ``CURRENT`` naming a complete generation (the one before, while the new one is
unfinished), so a resume always finds one it can read; the SHA-256 of every rank file
in the manifest catches a file that is not what was written.

The state files are Python pickles written by this package: load only checkpoints of
your own runs.

Signals: :func:`stop_on_signals` turns SIGINT and SIGTERM into a request to stop (a
flag). The solvers look at it at their safe points (after a converged increment, every
``every`` explicit steps) through :meth:`Checkpointer.safe_point`, which agrees on it
over the ranks (one allreduce), writes a checkpoint and raises :class:`Interrupted`.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import pickle
import shutil
import signal
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from mpi4py import MPI

__all__ = ["CHECKPOINT_DIR", "CheckpointError", "Checkpointer", "Interrupted",
           "clear_stop", "read_manifest", "rearm", "request_stop", "stop_on_signals",
           "stop_requested"]

CHECKPOINT_DIR = "checkpoint"
FORMAT_VERSION = 1
EXIT_INTERRUPTED = 130


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be used: missing, corrupt, of another number of ranks,
    another kind of run or another case."""


class Interrupted(Exception):  # noqa: N818  (a stop on request, not an error)
    """The run stopped on request (a signal) at a safe point after writing a checkpoint.

    Attributes:
        folder: the run folder holding the checkpoint.
        step: the step or increment count of the checkpoint.
    """

    def __init__(self, folder: Path, step: int, message: str | None = None, ranks: int = 1):
        self.folder = Path(folder)
        self.step = int(step)
        launch = f"mpirun -n {ranks} " if ranks > 1 else ""
        super().__init__(message or (
            f"interrupted: checkpoint written at step {step} in {self.folder}; "
            f"resume with: {launch}masonry-fdem assess --resume {self.folder}"))


# ------------------------------------------------------------------------------ signals
_STOP: dict[str, int | None] = {"signal": None}
_ARMED: dict[str, bool] = {"on": False}


def request_stop(signum: int = signal.SIGINT) -> None:
    """Ask the running solver to stop at its next safe point (what the signal handler
    does; tests call it from a callback)."""
    _STOP["signal"] = int(signum)


def stop_requested() -> bool:
    """Whether a stop was asked for on this rank."""
    return _STOP["signal"] is not None


def clear_stop() -> None:
    """Forget a stop request."""
    _STOP["signal"] = None


def _handler(signum, frame) -> None:  # noqa: ARG001
    if signum == signal.SIGINT and stop_requested():
        raise KeyboardInterrupt  # a second Ctrl-C: no waiting for the safe point
    request_stop(signum)


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Within the block, SIGINT and SIGTERM set the stop flag instead of ending the
    process (a second SIGINT raises KeyboardInterrupt at once; the previous handlers
    come back after the block; the main thread only)."""
    clear_stop()
    old = {}
    try:
        for s in (signal.SIGINT, signal.SIGTERM):
            try:
                old[s] = signal.signal(s, _handler)
            except ValueError:  # not the main thread: leave the signals alone
                pass
        _ARMED["on"] = bool(old)
        yield
    finally:
        _ARMED["on"] = False
        for s, h in old.items():
            signal.signal(s, h)
        clear_stop()


def rearm() -> None:
    """Within :func:`stop_on_signals`, install its handlers again: a library may have
    set the process's handlers behind Python's back (the mesh generator resets SIGTERM
    to the default, which ends the process). Called at every safe point."""
    if _ARMED["on"]:
        for s in (signal.SIGINT, signal.SIGTERM):
            with contextlib.suppress(ValueError):
                signal.signal(s, _handler)


# ------------------------------------------------------------------------------ files
def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _write_atomic(path: Path, data: bytes) -> None:
    """``data`` into ``path`` through ``path.tmp``, flushed to disk, renamed in place."""
    tmp = path.with_name(path.name + ".tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _dump(obj: Any, path: Path) -> None:
    _write_atomic(path, pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def read_manifest(folder: str | Path) -> dict:
    """The manifest of the current checkpoint of run folder ``folder`` (with
    ``"generation"``: its folder), or CheckpointError."""
    root = Path(folder) / CHECKPOINT_DIR
    cur = root / "CURRENT"
    if not cur.is_file():
        raise CheckpointError(f"no checkpoint in {folder} (no {cur})")
    name = cur.read_text().strip()
    gen = root / name
    try:
        manifest = json.loads((gen / "manifest.json").read_text())
    except (OSError, ValueError) as exc:
        raise CheckpointError(f"checkpoint {gen}: unreadable manifest ({exc})") from None
    if manifest.get("version") != FORMAT_VERSION:
        raise CheckpointError(f"checkpoint {gen}: format version {manifest.get('version')}, "
                              f"this package reads {FORMAT_VERSION}")
    manifest["generation"] = str(gen)
    return manifest


class Checkpointer:
    """Writes and reads the checkpoints of one run folder (collective over ``comm``).

    Args:
        folder: the run folder (the checkpoints go to ``folder/checkpoint``).
        comm: MPI communicator of the run.
        kind: what runs ("explicit", "assess"): a resume checks it.
        every: write a checkpoint every ``every`` safe points (steps of the explicit
            solver at which it checks its state, converged increments of path
            following); 0: only when stopped by a signal.
        meta: JSON-able facts a resume must find again (e.g. ``{"case_sha256": ...}``);
            :meth:`read` compares them and names the first that differs.
    """

    def __init__(self, folder: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, *,
                 kind: str = "run", every: int = 0, meta: dict | None = None):
        if every < 0:
            raise ValueError(f"every must be >= 0, got {every}")
        self.folder = Path(folder)
        self.root = self.folder / CHECKPOINT_DIR
        self.comm = comm
        self.kind = str(kind)
        self.every = int(every)
        self.meta = dict(meta or {})
        self.written = 0  # generations written by this object

    # -------------------------------------------------------------------- the safe point
    def safe_point(self, count: int, state: Callable[[], dict]) -> bool:
        """At a safe point of the run (collective): write ``state()`` (this rank's state,
        a picklable dict) when ``count`` is a multiple of :attr:`every` or a stop was
        requested on any rank; on a stop, raise :class:`Interrupted` after writing.

        Returns:
            Whether a checkpoint was written.
        """
        rearm()
        stop = bool(self.comm.allreduce(stop_requested(), op=MPI.LOR))
        due = stop or (self.every > 0 and count > 0 and count % self.every == 0)
        if due:
            self.write(state(), count)
        if stop:
            raise Interrupted(self.folder, count, ranks=self.comm.size)
        return due

    # -------------------------------------------------------------------- writing
    def write(self, state: dict, step: int) -> Path:
        """Write a new generation holding ``state`` (this rank's) at ``step`` and make it
        the current one (collective; see the module doc for the order)."""
        comm = self.comm
        error = None
        gen = None
        if comm.rank == 0:
            try:
                self.root.mkdir(parents=True, exist_ok=True)
                last = self._generations()
                n = (int(last[-1][1:]) + 1) if last else 1
                gen = self.root / f"g{n:06d}"
                if gen.exists():
                    shutil.rmtree(gen)
                gen.mkdir()
            except OSError as exc:
                error = f"checkpoint: cannot create a generation in {self.root}: {exc}"
        gen, error = comm.bcast((gen, error), root=0)
        if error:
            raise CheckpointError(error)
        path = gen / f"rank{comm.rank}.pkl"
        try:
            _dump(state, path)
            digest = _sha256(path)
        except OSError as exc:
            digest, error = None, f"checkpoint: writing {path}: {exc}"
        errors = comm.allgather(error)
        if any(errors):
            raise CheckpointError(next(e for e in errors if e))
        digests = comm.gather(digest, root=0)
        if comm.rank == 0:
            try:
                manifest = {"version": FORMAT_VERSION, "kind": self.kind,
                            "n_ranks": comm.size, "step": int(step),
                            "files": {f"rank{r}.pkl": d for r, d in enumerate(digests)},
                            **self.meta}
                _write_atomic(gen / "manifest.json",
                              json.dumps(manifest, indent=1).encode())
                cur = self.root / "CURRENT"
                before = cur.read_text().strip() if cur.is_file() else None
                _write_atomic(cur, f"{gen.name}\n".encode())
                # keep the new generation and the one current before it
                for old in self._generations():
                    if old not in (gen.name, before):
                        shutil.rmtree(self.root / old, ignore_errors=True)
            except OSError as exc:
                error = f"checkpoint: writing {gen}: {exc}"
        error = comm.bcast(error, root=0)
        if error:
            raise CheckpointError(error)
        self.written += 1
        return gen

    def _generations(self) -> list[str]:
        if not self.root.is_dir():
            return []
        return sorted(p.name for p in self.root.iterdir()
                      if p.is_dir() and p.name.startswith("g") and p.name[1:].isdigit())

    def remove(self) -> None:
        """Remove every checkpoint of the folder (a finished run; collective)."""
        if self.comm.rank == 0 and self.root.exists():
            shutil.rmtree(self.root, ignore_errors=True)
        self.comm.barrier()

    # -------------------------------------------------------------------- reading
    def exists(self) -> bool:
        """Whether the folder holds a current checkpoint (collective)."""
        ok = (self.root / "CURRENT").is_file() if self.comm.rank == 0 else None
        return bool(self.comm.bcast(ok, root=0))

    def read(self) -> tuple[dict, dict]:
        """``(manifest, this rank's state)`` of the current checkpoint (collective).

        Raises:
            CheckpointError: none, unreadable, corrupt, written by another number of
                ranks, another kind of run, or with other :attr:`meta`.
        """
        comm = self.comm
        manifest, error = None, None
        if comm.rank == 0:
            try:
                manifest = read_manifest(self.folder)
            except CheckpointError as exc:
                error = str(exc)
        manifest, error = comm.bcast((manifest, error), root=0)
        if error:
            raise CheckpointError(error)
        gen = Path(manifest["generation"])
        if manifest["n_ranks"] != comm.size:
            raise CheckpointError(
                f"checkpoint {gen} was written by {manifest['n_ranks']} MPI rank(s); this "
                f"run has {comm.size}: resume with mpirun -n {manifest['n_ranks']}")
        if manifest.get("kind") != self.kind:
            raise CheckpointError(f"checkpoint {gen} is of a {manifest.get('kind')!r} run, "
                                  f"not {self.kind!r}")
        for key, value in self.meta.items():
            if manifest.get(key) != value:
                if key == "case_sha256":
                    raise CheckpointError(
                        f"checkpoint {gen}: the case changed since the run began (its "
                        f"SHA-256 was {manifest.get(key)}, is {value}): start afresh "
                        "(--overwrite) or restore the case file")
                raise CheckpointError(
                    f"checkpoint {gen}: {key} differs from the run's "
                    f"({manifest.get(key)!r} then, {value!r} now)")
        path = gen / f"rank{comm.rank}.pkl"
        state = None
        try:
            if _sha256(path) != manifest["files"][path.name]:
                error = f"checkpoint {path}: corrupt (its SHA-256 is not the manifest's)"
            else:
                with open(path, "rb") as f:
                    state = pickle.load(f)
        except (OSError, KeyError, pickle.UnpicklingError, EOFError) as exc:
            error = f"checkpoint {path}: unreadable ({exc!r})"
        errors = comm.allgather(error)
        if any(errors):
            raise CheckpointError(next(e for e in errors if e))
        return manifest, state
