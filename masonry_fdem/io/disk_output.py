"""ParaView output of disks: a time series of VTK PolyData point clouds.

Each call of :meth:`DiskOutput.write` writes ``disks_<k>.vtp`` (points at the disk centres
with point data radius [m], velocity [m/s], angular velocity [rad/s], rotation [rad] and
the contact force on the disk [N]; point k is disk k of the user's numbering, the order
the disks were given in, in every file — whatever order the set stores them in — and the
point data ``id`` says so) and rewrites ``disks.pvd``, the collection ParaView
opens as one time series. Draw the disks with the "Glyph" filter (sphere or 2D glyph,
scale array "radius", scale factor 2). Written by rank 0 (every rank holds every disk).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from masonry_fdem.io._vtk import float_array as _array
from masonry_fdem.io._vtk import int_array, write_collection

__all__ = ["DiskOutput"]


class DiskOutput:
    """Writes the disks at chosen times (rank 0).

    Args:
        disks: the :class:`~masonry_fdem.interactions.disks.Disks` set.
        folder: output folder (created).
    """

    def __init__(self, disks, folder: str | Path):
        self.disks = disks
        self.folder = Path(folder)
        self.steps: list[tuple[float, str]] = []
        if disks.comm.rank == 0:
            self.folder.mkdir(parents=True, exist_ok=True)

    def write(self, t: float) -> None:
        """Write the disk state at time t [s]."""
        d = self.disks
        if d.comm.rank != 0:
            return
        name = f"disks_{len(self.steps):05d}.vtp"
        b = d.by_id  # storage order -> the user's numbering
        pts = np.c_[b(d.x), np.zeros(d.n)]
        vel = np.c_[b(d.v), np.zeros(d.n)]
        fc = np.c_[b(d.f), np.zeros(d.n)]  # contact (and coupling) forces at the step
        offsets = np.arange(1, d.n + 1, dtype="<i8")
        conn = np.arange(d.n, dtype="<i8")

        xml = (
            '<?xml version="1.0"?>\n'
            '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">\n<PolyData>\n'
            f'<Piece NumberOfPoints="{d.n}" NumberOfVerts="{d.n}" NumberOfLines="0" '
            'NumberOfStrips="0" NumberOfPolys="0">\n'
            f"<Points>{_array('Points', pts, 3)}</Points>\n"
            f"<Verts>{int_array('connectivity', conn)}{int_array('offsets', offsets)}</Verts>\n"
            '<PointData Scalars="radius" Vectors="velocity">\n'
            f"{_array('radius', b(d.r), 1)}\n{_array('velocity', vel, 3)}\n"
            f"{_array('angular_velocity', b(d.omega), 1)}\n"
            f"{_array('rotation', b(d.theta), 1)}\n"
            f"{_array('contact_force', fc, 3)}\n{int_array('id', conn)}\n"
            "</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n"
        )
        (self.folder / name).write_text(xml)
        self.steps.append((float(t), name))
        write_collection(self.folder / "disks.pvd", self.steps)
