"""Run folders: one check of a folder before a run writes into it, and the hand-over of a
finished hidden ``.<name>.partial`` folder, so that a failed run leaves nothing behind."""

from __future__ import annotations

import shutil
from pathlib import Path
from collections.abc import Callable
from typing import Any

__all__ = ["hand_over", "move_into", "partial_folder", "run_folder_problem"]


def run_folder_problem(folder: Path, *, overwrite: bool = False, resume: bool | None = None,
                       create: bool = False, key: str = "output",
                       comm: Any | None = None) -> str | None:
    """Why ``folder`` cannot take a run, or None (collective over ``comm``; rank 0 looks).

    Args:
        folder: the run folder.
        overwrite: a folder that exists and is not empty may be used (its files are
            replaced as the run writes them); with ``resume`` given, it is emptied first.
        resume: None: the run cannot resume; True/False: it can, and does (a non-empty
            folder is then fine).
        create: create the folder (and its parents).
        key: the case key named in the message.
        comm: MPI communicator, or None for this process alone.
    """
    error = None
    if comm is None or comm.rank == 0:
        if folder.exists() and not folder.is_dir():
            error = f"{key}: {folder} exists and is not a folder"
        elif folder.is_dir() and any(folder.iterdir()) and not (overwrite or resume):
            how = "overwrite it" if resume is None else "resume or overwrite it"
            sep = " or " if resume is None else ", "
            error = (f"{key}: the folder {folder} exists and is not empty; choose another "
                     f"output{sep}{how}")
        elif overwrite and resume is not None and folder.is_dir():
            shutil.rmtree(folder)
        if error is None and create:
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                error = f"{key}: cannot create {folder}: {e.strerror or e}"
    return comm.bcast(error, root=0) if comm is not None else error


def partial_folder(folder: Path) -> Path:
    """The hidden folder a run writes into before :func:`move_into` hands it over."""
    return folder.parent / f".{folder.name}.partial"


def move_into(tmp: Path, folder: Path) -> None:
    """Move every entry of the finished folder ``tmp`` into ``folder`` (created if need
    be; an entry of the same name is replaced) and remove ``tmp``."""
    folder.mkdir(parents=True, exist_ok=True)
    for f in sorted(tmp.iterdir()):
        dest = folder / f.name
        if dest.is_dir() and not dest.is_symlink():
            shutil.rmtree(dest)
        f.replace(dest)
    tmp.rmdir()


def hand_over(write: Callable[[Path], None], tmp: Path, folder: Path, comm: Any) -> None:
    """On rank 0, ``write(tmp)`` and :func:`move_into` ``folder``; a failure there reaches
    every rank as RuntimeError (no rank waits for one that failed; collective)."""
    error = None
    if comm.rank == 0:
        try:
            write(tmp)
            move_into(tmp, folder)
        except Exception as exc:
            error = f"writing the run folder {folder}: {exc!r}"
    error = comm.bcast(error, root=0)
    if error:
        raise RuntimeError(error)
