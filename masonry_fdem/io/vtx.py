"""ParaView output through dolfinx's VTXWriter (ADIOS2 BP files).

Two time series in the run folder: ``displacement.bp`` (nodal displacement and velocity,
P1) and ``stress.bp`` (Cauchy stress per cell, DG0); with bonded joints a third,
``joints.bp``: the worst joint state along each cell's edges (DG0; 0 intact, 1 softening,
2 open, 3 sliding, 4 crushed, see :data:`masonry_fdem.interactions.JOINT_STATES`). Open them in ParaView with the ADIOS2
VTX reader and apply "Warp By Vector" on the displacement. Models with history or plastic
laws also get ``materials.bp`` (DG0): history variables such as "kappa", the "damage",
"plastic_strain" (accumulated α) and "plastic_work_density" [J/m³].

Beside the ``.bp`` series, the same states as plain VTK files that any ParaView (and
meshio) opens: ``model.pvd``, a collection of ``model_<k>.vtu`` files (one per write),
each the whole block mesh in the order of the :class:`~masonry_fdem.geometry.BlockMesh`
(its points and triangles), with point data "displacement" [m] and "velocity" [m/s]
(z = 0 as the third component, for "Warp By Vector") and cell data "stress" (Cauchy
stress [Pa], components xx, xy, yx, yy), "block" (block id) and, when written to the
``.bp`` files, the material fields and "joint_state". Under MPI the ranks send their
nodes and cells to rank 0, which writes one ``.vtu`` per step (no ``.pvtu`` pieces).
"""

from __future__ import annotations

from pathlib import Path

import masonry_fdem._compat  # noqa: F401
import dolfinx
import dolfinx.fem
import dolfinx.io
import numpy as np

from masonry_fdem.io._vtk import write_collection

__all__ = ["VTXOutput"]


class VTXOutput:
    """Writes the model state at chosen times (collective).

    Args:
        model: the model.
        folder: output folder (created).
        joints: the :class:`~masonry_fdem.interactions.Joints` whose state is written.
        vtu: also write the ``.vtu`` files and the ``model.pvd`` collection.
    """

    def __init__(self, model, folder: str | Path, joints=None, vtu: bool = True):
        self.model = model
        self.vtu = bool(vtu)
        self._steps: list[tuple[float, str]] = []
        self.joints = joints
        self.folder = Path(folder)
        if model.comm.rank == 0:
            self.folder.mkdir(parents=True, exist_ok=True)
        model.comm.barrier()
        self.velocity = dolfinx.fem.Function(model.V, name="velocity")
        self._nodal = dolfinx.io.VTXWriter(
            model.comm, self.folder / "displacement.bp", [model.u, self.velocity],
            engine="BP4",
        )
        self._cell = dolfinx.io.VTXWriter(
            model.comm, self.folder / "stress.bp", [model.stress], engine="BP4"
        )
        # material state (damage, plastic strain), DG0
        self._mat = None
        fields = model.material_fields()
        if fields:
            Q = dolfinx.fem.functionspace(model.mesh, ("DG", 0))
            self.material = {n: dolfinx.fem.Function(Q, name=n) for n in fields}
            self._mat = dolfinx.io.VTXWriter(
                model.comm, self.folder / "materials.bp", list(self.material.values()),
                engine="BP4")
        self._joint = None
        if joints is not None:
            Q = dolfinx.fem.functionspace(model.mesh, ("DG", 0))
            self.joint_state = dolfinx.fem.Function(Q, name="joint_state")
            self._joint = dolfinx.io.VTXWriter(
                model.comm, self.folder / "joints.bp", [self.joint_state], engine="BP4"
            )

    def write(self, t: float, velocity=None) -> None:
        """Write displacement [m], velocity [m/s] and Cauchy stress [Pa] at time t [s]."""
        if velocity is None:
            velocity = self.model.v
        self.velocity.x.array[:] = velocity
        self.model.update_stress()
        self._nodal.write(t)
        self._cell.write(t)
        if self._mat is not None:
            for n, vals in self.model.material_fields().items():
                f = self.material[n]
                f.x.array[: vals.size] = vals
                f.x.scatter_forward()
            self._mat.write(t)
        if self._joint is not None:
            state = self.joints.cell_state()
            cells = self.model.dmesh.cell_input
            self.joint_state.x.array[: cells.size] = state[cells]
            self.joint_state.x.scatter_forward()
            self._joint.write(t)
        if self.vtu:
            self._write_vtu(t)

    def _write_vtu(self, t: float) -> None:
        """Gather the state on rank 0 and write ``model_<k>.vtu`` and ``model.pvd``."""
        model = self.model
        comm = model.comm
        n_cells = model.dmesh.cell_input.size
        cell = {"stress": model.stress.x.array.reshape(-1, 4)[:n_cells]}
        if self._mat is not None:
            for n, f in self.material.items():
                cell[n] = f.x.array[:n_cells]
        if self._joint is not None:
            cell["joint_state"] = self.joint_state.x.array[:n_cells]
        nodal = {"displacement": model.u.x.array.reshape(-1, 2)[: model.n_nodes],
                 "velocity": self.velocity.x.array.reshape(-1, 2)[: model.n_nodes]}
        parts = comm.gather((model.node_input, nodal, model.dmesh.cell_input, cell), root=0)
        if comm.rank == 0:
            import meshio

            bm = model.blocks
            point_data = {n: np.zeros((bm.n_nodes, 3)) for n in nodal}
            cell_data = {n: np.zeros((bm.n_cells,) + np.shape(v)[1:]) for n, v in cell.items()}
            for nodes, nd, cells, cd in parts:
                for n, v in nd.items():
                    point_data[n][nodes, :2] = v
                for n, v in cd.items():
                    cell_data[n][cells] = v
            cell_data["block"] = bm.cell_block.astype(np.int64)
            name = f"model_{len(self._steps):06d}.vtu"
            mesh = meshio.Mesh(np.c_[bm.x, np.zeros(bm.n_nodes)], [("triangle", bm.cells)],
                               point_data=point_data,
                               cell_data={n: [v] for n, v in cell_data.items()})
            meshio.write(self.folder / name, mesh, file_format="vtu")
            self._steps.append((float(t), name))
            write_collection(self.folder / "model.pvd", self._steps)

    def close(self) -> None:
        self._nodal.close()
        self._cell.close()
        if self._mat is not None:
            self._mat.close()
        if self._joint is not None:
            self._joint.close()

    def __enter__(self) -> VTXOutput:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
