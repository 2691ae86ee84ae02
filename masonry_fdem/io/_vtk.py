"""Pieces of VTK XML files shared by the ParaView writers of disks and anchors."""

from __future__ import annotations

import base64
from pathlib import Path

import numpy as np


def _payload(data: bytes) -> str:
    header = np.array([len(data)], dtype="<u8").tobytes()
    return base64.b64encode(header).decode() + base64.b64encode(data).decode()


def float_array(name: str, values: np.ndarray, components: int) -> str:
    """A binary Float64 ``DataArray`` element."""
    data = np.ascontiguousarray(values, dtype="<f8").tobytes()
    return (f'<DataArray type="Float64" Name="{name}" NumberOfComponents="{components}" '
            f'format="binary">{_payload(data)}</DataArray>')


def int_array(name: str, values: np.ndarray) -> str:
    """A binary Int64 ``DataArray`` element."""
    data = np.ascontiguousarray(values, dtype="<i8").tobytes()
    return f'<DataArray type="Int64" Name="{name}" format="binary">{_payload(data)}</DataArray>'


def write_collection(path: Path, steps: list[tuple[float, str]]) -> None:
    """(Re)write the ``.pvd`` collection of a time series of (time, file name) steps."""
    rows = "\n".join(f'<DataSet timestep="{t:.9g}" file="{fn}"/>' for t, fn in steps)
    path.write_text('<?xml version="1.0"?>\n<VTKFile type="Collection" version="1.0">\n'
                    f"<Collection>\n{rows}\n</Collection>\n</VTKFile>\n")
