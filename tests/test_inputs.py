"""Bad input gets a clear error naming the problem."""

from mpi4py import MPI

import numpy as np
import pytest
from conftest import rectangle

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks, read_msh
from masonry_fdem.solvers import ExplicitSolver, UnstableTimeStepError

comm = MPI.COMM_WORLD


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"density": 2000.0, "E": 0.0, "nu": 0.2}, "Young's modulus E must be > 0"),
        ({"density": 2000.0, "E": -1e9, "nu": 0.2}, "Young's modulus E must be > 0"),
        ({"density": 2000.0, "E": 1e9, "nu": 0.5}, "Poisson's ratio nu"),
        ({"density": 2000.0, "E": 1e9, "nu": 0.7}, "Poisson's ratio nu"),
        ({"density": 0.0, "E": 1e9, "nu": 0.2}, "density must be > 0"),
        ({"density": -5.0, "E": 1e9, "nu": 0.2}, "density must be > 0"),
        ({"density": float("nan"), "E": 1e9, "nu": 0.2}, "density must be a finite number"),
        ({"density": 2000.0, "E": None, "nu": 0.2}, "E must be a finite number"),
    ],
)
def test_bad_material_constants(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Material(**kwargs)


def test_missing_mesh_file(tmp_path):
    missing = tmp_path / "no_such_bridge.msh"
    with pytest.raises(FileNotFoundError, match="no_such_bridge.msh"):
        read_msh(missing, comm=comm)


def _msh_without_groups(path):
    import gmsh

    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("nogroups")
        gmsh.model.occ.addRectangle(0, 0, 0, 1, 0.5)
        gmsh.model.occ.synchronize()
        gmsh.model.mesh.generate(2)
        gmsh.write(str(path))
        gmsh.finalize()
    comm.barrier()


def test_mesh_without_physical_groups(tmp_path):
    path = tmp_path / "nogroups.msh"
    path = comm.bcast(path, root=0)
    _msh_without_groups(path)
    with pytest.raises(ValueError, match="physical"):
        read_msh(path, blocks="physical", comm=comm)


def test_3d_mesh_is_refused(tmp_path):
    import gmsh

    path = comm.bcast(tmp_path / "box.msh", root=0)
    if comm.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("box")
        gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        gmsh.model.addPhysicalGroup(3, [1], name="block")
        gmsh.model.mesh.generate(3)
        gmsh.write(str(path))
        gmsh.finalize()
    comm.barrier()
    with pytest.raises(ValueError, match="3D"):
        read_msh(path, comm=comm)


def test_model_errors():
    blocks = mesh_blocks([rectangle(0, 0, 1, 0.5)], materials="brick", comm=comm)
    with pytest.raises(ValueError, match=r"no Material given for material name\(s\) \['brick'\]"):
        Model(blocks, {"stone": Material(2000.0, 1e9, 0.2)}, comm=comm)
    with pytest.raises(ValueError, match="width must be > 0"):
        Model(blocks, {"brick": Material(2000.0, 1e9, 0.2)}, width=0.0, comm=comm)
    with pytest.raises(ValueError, match="plane_strainn"):
        Model(blocks, {"brick": Material(2000.0, 1e9, 0.2)}, hypothesis="plane_strainn")
    model = Model(blocks, {"brick": Material(2000.0, 1e9, 0.2)}, comm=comm)
    with pytest.raises(ValueError, match="no block named 'wall:3'"):
        model.fix_blocks("wall:3")
    with pytest.raises(ValueError, match="locator selects no node"):
        model.fix(lambda X: X[0] < -1.0)
    with pytest.raises(ValueError, match="selects no block boundary facet"):
        model.add_line_load(lambda x: x[1] > 10.0, (0.0, -1.0))


def test_time_step_above_stable_one():
    blocks = mesh_blocks([rectangle(0, 0, 1, 0.5)], materials="brick", comm=comm)
    model = Model(blocks, {"brick": Material(2000.0, 1e9, 0.2)}, comm=comm)
    with pytest.raises(UnstableTimeStepError, match=r"time step 1 s exceeds the stable time step"):
        ExplicitSolver(model, dt=1.0)
    # the stable step itself is reported and used
    solver = ExplicitSolver(model)
    assert solver.dt == pytest.approx(0.9 * solver.dt_critical)
    assert np.isfinite(solver.dt_critical) and solver.dt_critical > 0
