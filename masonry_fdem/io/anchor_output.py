"""ParaView output of anchors: a time series of VTK PolyData lines.

Each call of :meth:`AnchorOutput.write` writes ``anchors_<k>.vtp`` — one line cell per bar
element at its current position, with cell data ``axial_force`` [N per bar, tension
positive], ``stress`` [Pa], ``plastic_strain`` [-], ``ruptured`` (0/1) and ``anchor`` (index),
and point data ``displacement`` [m], ``slip`` [m] and ``bond_stress`` [Pa] (means over a
node's bond points; 0 where the bar is outside the masonry) — and rewrites
``anchors.pvd``, the collection ParaView opens as one time series. Collective (the bond
results are summed over ranks); rank 0 writes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from masonry_fdem.io._vtk import float_array as _array
from masonry_fdem.io._vtk import int_array, write_collection

__all__ = ["AnchorOutput"]


class AnchorOutput:
    """Writes the anchors at chosen times.

    Args:
        anchors: the :class:`~masonry_fdem.interactions.anchors.Anchors`.
        folder: output folder (created).
    """

    def __init__(self, anchors, folder: str | Path):
        self.anchors = anchors
        self.folder = Path(folder)
        self.steps: list[tuple[float, str]] = []
        if anchors.comm.rank == 0:
            self.folder.mkdir(parents=True, exist_ok=True)

    def write(self, t: float) -> None:
        """Write the anchor state at time (or load step) t (collective)."""
        a = self.anchors
        res = a.node_results()
        if a.comm.rank != 0:
            return
        name = f"anchors_{len(self.steps):05d}.vtp"
        n, ne = a.n, a.n_elements
        pts = np.c_[res["position"], np.zeros(n)]
        disp = np.c_[a.u.reshape(-1, 2), np.zeros(n)]
        cells = "\n".join([
            _array("axial_force", a.axial_force(), 1),
            _array("stress", a.stress(), 1),
            _array("plastic_strain", a.plastic_strain(), 1),
            _array("ruptured", a.ruptured().astype(float), 1),
            _array("anchor", a.elem_anchor.astype(float), 1),
        ])
        points = "\n".join([
            _array("displacement", disp, 3),
            _array("slip", res["slip"], 1),
            _array("bond_stress", res["bond_stress"], 1),
        ])
        xml = (
            '<?xml version="1.0"?>\n'
            '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" '
            'header_type="UInt64">\n<PolyData>\n'
            f'<Piece NumberOfPoints="{n}" NumberOfVerts="0" NumberOfLines="{ne}" '
            'NumberOfStrips="0" NumberOfPolys="0">\n'
            f"<Points>{_array('Points', pts, 3)}</Points>\n"
            f"<Lines>{int_array('connectivity', a.conn.ravel())}"
            f"{int_array('offsets', 2 * np.arange(1, ne + 1))}</Lines>\n"
            f'<PointData Scalars="slip" Vectors="displacement">\n{points}\n</PointData>\n'
            f'<CellData Scalars="axial_force">\n{cells}\n</CellData>\n'
            "</Piece>\n</PolyData>\n</VTKFile>\n"
        )
        (self.folder / name).write_text(xml)
        self.steps.append((float(t), name))
        write_collection(self.folder / "anchors.pvd", self.steps)
