"""Gmsh sessions that leave the caller's Gmsh state as they found it, and rank-0 work.

Gmsh is a process-wide singleton. :func:`gmsh_model` initialises it only if nobody else has,
works in a fresh model, restores every option it touched and the caller's current model,
and finalises only what it initialised. :func:`on_root` runs a function on rank 0 of a
communicator and broadcasts its result, or its exception, to every rank, so a Gmsh error
on rank 0 is raised everywhere instead of leaving the other ranks waiting.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

import gmsh

log = logging.getLogger(__name__)

T = TypeVar("T")

_counter = itertools.count()


@contextmanager
def gmsh_model(options: dict[str, float] | None = None) -> Iterator[str]:
    """Work in a fresh Gmsh model with some numeric options set, then clean up.

    Args:
        options: Gmsh numeric options to set for the duration (restored afterwards).
            ``General.Terminal`` is always set to 0 (quiet).

    Yields:
        The name of the temporary model (it is the current model inside the block).
    """
    owner = not gmsh.isInitialized()
    if owner:
        gmsh.initialize(readConfigFiles=False, interruptible=False)
    previous = None
    if not owner:
        try:
            previous = gmsh.model.getCurrent()
        except Exception:  # no current model
            previous = None
    opts = {"General.Terminal": 0.0, **(options or {})}
    saved = {k: gmsh.option.getNumber(k) for k in opts}
    for k, v in opts.items():
        gmsh.option.setNumber(k, float(v))
    name = f"masonry_fdem_{next(_counter)}"
    gmsh.model.add(name)
    try:
        yield name
    finally:
        try:
            gmsh.model.setCurrent(name)
            gmsh.model.remove()
            if previous:
                gmsh.model.setCurrent(previous)
        finally:
            for k, v in saved.items():
                gmsh.option.setNumber(k, v)
            if owner:
                gmsh.finalize()


def on_root(comm: Any | None, work: Callable[[], T]) -> T:
    """Run ``work`` on rank 0 and broadcast the result (collective if ``comm`` is given).

    Args:
        comm: an mpi4py communicator, or None to run ``work`` here.
        work: a function of no arguments; its result must be picklable.

    Returns:
        The result of ``work`` on every rank.

    Raises:
        Exception: whatever ``work`` raised on rank 0, re-raised on every rank.
    """
    if comm is None or comm.size == 1:
        return work()
    payload: tuple[bool, Any] | None = None
    error: BaseException | None = None
    if comm.rank == 0:
        try:
            payload = (True, work())
        except Exception as exc:
            error = exc
            payload = (False, exc)
    ok, value = comm.bcast(payload, root=0)
    if not ok:
        if error is not None:
            raise error
        raise value
    return value
