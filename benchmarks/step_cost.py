"""Cost of one explicit step against a bare dolfinx assembly of the same form.

For models of about 1e3 to 2e5 P1 triangles (a running-bond brick wall, each brick its
own block) this prints the median time of

* the bare baseline: the internal-force form assembled by dolfinx into a preallocated
  array (``dolfinx.fem.assemble_vector(array, form)``, zeroed first, dolfinx packing the
  coefficients), as the step assembles — no new vector per call, which would flatter
  the step — and
* one full explicit step of ``ExplicitSolver`` (coefficient packing, assembly into a
  preallocated array, the numba update of velocities/displacements/energies),

their ratio (goal <= 1.3), and the per-step cost of a tiny model (goal <= 50 us).
Run: ``python benchmarks/step_cost.py [--sizes 1e3 1e4 ...]``.
"""

import argparse
import statistics
import time

from mpi4py import MPI

import numpy as np

import masonry_fdem  # noqa: F401
import dolfinx.fem

from masonry_fdem import Material, Model
from masonry_fdem.geometry import mesh_blocks
from masonry_fdem.solvers import ExplicitSolver


def median_times(fns, reps: int, rounds: int = 9) -> list[float]:
    """Median time per call of each function; rounds interleave the functions so that
    clock-frequency drift affects all of them alike."""
    samples = [[] for _ in fns]
    for _ in range(rounds):
        for k, fn in enumerate(fns):
            t0 = time.perf_counter()
            for _ in range(reps):
                fn()
            samples[k].append((time.perf_counter() - t0) / reps)
    return [statistics.median(s) for s in samples]


def wall_blocks(n_cells_target: int):
    """Bricks 0.2 x 0.1 m, ~2 * (0.1/h)^2 * 2 cells each, arranged in a square wall."""
    brick_l, brick_h = 0.2, 0.1
    h = 0.025 if n_cells_target >= 5000 else 0.05
    one = np.array([[0, 0], [brick_l, 0], [brick_l, brick_h], [0, brick_h]])
    cells_per_brick = mesh_blocks([one], materials="brick", mesh_size=h).n_cells
    n_bricks = max(1, int(round(n_cells_target / cells_per_brick)))
    n_per_course = max(1, int(np.sqrt(n_bricks / 2)))
    courses = max(1, int(np.ceil(n_bricks / n_per_course)))
    polys = []
    for c in range(courses):
        for b in range(n_per_course):
            x0 = b * brick_l + (0.5 * brick_l if c % 2 else 0.0)
            y0 = c * brick_h
            polys.append(np.array([[x0, y0], [x0 + brick_l, y0], [x0 + brick_l, y0 + brick_h],
                                   [x0, y0 + brick_h]]))
    return mesh_blocks(polys, materials="brick", mesh_size=h, comm=MPI.COMM_WORLD)


def measure(blocks, reps):
    model = Model(blocks, {"brick": Material(1800.0, 5e9, 0.2)}, comm=MPI.COMM_WORLD)
    model.add_gravity()
    solver = ExplicitSolver(model)
    solver.run(steps=5)  # warm up (JIT, caches)
    out = np.zeros_like(model.f_int)

    def bare():
        out.fill(0.0)
        dolfinx.fem.assemble_vector(out, model.f_int_form)

    bare, step = median_times([bare, solver.step], reps)
    return model, bare, step


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=float, nargs="+", default=[1e3, 1e4, 5e4, 2e5])
    args = parser.parse_args()
    rank0 = MPI.COMM_WORLD.rank == 0
    if rank0:
        print(f"{'cells':>8} {'bare assemble [us]':>19} {'full step [us]':>15} "
              f"{'ns/cell':>8} {'ratio':>6}")
    for n in args.sizes:
        blocks = wall_blocks(int(n))
        reps = max(5, int(2e6 / blocks.n_cells))
        model, bare, step = measure(blocks, reps)
        if rank0:
            print(f"{blocks.n_cells:8d} {1e6 * bare:19.1f} {1e6 * step:15.1f} "
                  f"{1e9 * step / blocks.n_cells:8.1f} {step / bare:6.2f}")
    tiny = mesh_blocks([np.array([[0, 0], [0.2, 0], [0.2, 0.1], [0, 0.1]])], materials="brick",
                       comm=MPI.COMM_WORLD)
    model, bare, step = measure(tiny, 20000)
    if rank0:
        print(f"tiny model ({tiny.n_cells} cells): full step {1e6 * step:.1f} us "
              f"(bare assemble {1e6 * bare:.1f} us, ratio {step / bare:.2f}); goal <= 50 us")


if __name__ == "__main__":
    main()
