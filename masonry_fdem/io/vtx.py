"""ParaView output through dolfinx's VTXWriter (ADIOS2 BP files).

Two time series in the run folder: ``displacement.bp`` (nodal displacement and velocity,
P1) and ``stress.bp`` (Cauchy stress per cell, DG0); with bonded joints a third,
``joints.bp``: the worst joint state along each cell's edges (DG0; 0 intact, 1 softening,
2 open, 3 sliding, 4 crushed, see :data:`masonry_fdem.interactions.JOINT_STATES`). Open them in ParaView with the ADIOS2
VTX reader and apply "Warp By Vector" on the displacement. Models with history or plastic
laws also get ``materials.bp`` (DG0): history variables such as "kappa", the "damage",
"plastic_strain" (accumulated α) and "plastic_work_density" [J/m³].
"""

from __future__ import annotations

from pathlib import Path

import masonry_fdem._compat  # noqa: F401
import dolfinx
import dolfinx.fem
import dolfinx.io

__all__ = ["VTXOutput"]


class VTXOutput:
    """Writes the model state at chosen times (collective).

    Args:
        model: the model.
        folder: output folder (created).
    """

    def __init__(self, model, folder: str | Path, joints=None):
        self.model = model
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
