"""Broad phase for disks: the numba cell list against the ADT of the disks' boxes (the
facets' machinery) and scipy's cKDTree, on dense polydisperse packings of 1e4 to 1e6 disks.

Each method returns the pairs closer than r_i + r_j + margin (the ADT's box pairs are
filtered by that distance; all three must agree). Prints the median time per disk of
a full search (build + query) and the ratios to the cell list, which decided the choice
in ``masonry_fdem.interactions.disks`` (cell list for disk–disk; the ADT stays for disk–facet pairs,
whose sizes differ widely).
Run: ``python benchmarks/disk_search.py [--sizes 1e4 1e5 1e6]``.
"""

import argparse
import statistics
import time

import numpy as np
from scipy.spatial import cKDTree

import masonry_fdem  # noqa: F401
from masonry_fdem.interactions.disks._kernels import disk_pairs_cell_list
from masonry_fdem.interactions.search.adt import self_pairs


def dense(n: int, seed: int = 0):
    """Jittered square lattice of disks with radii in [0.8, 1.2] × 0.5 mm (touching)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(n)))
    i, j = np.divmod(np.arange(n), side)
    h = 1e-3
    x = np.c_[i * h, j * h] + rng.uniform(-0.05, 0.05, (n, 2)) * h
    r = rng.uniform(0.4, 0.6, n) * h
    return x, r


def filtered(pairs, x, r, margin):
    d = np.linalg.norm(x[pairs[:, 0]] - x[pairs[:, 1]], axis=1)
    keep = d < r[pairs[:, 0]] + r[pairs[:, 1]] + margin
    p = np.sort(pairs[keep], axis=1)
    return p[np.lexsort((p[:, 1], p[:, 0]))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5, 1e6])
    args = ap.parse_args()
    print("disk broad phase, serial; median time per disk of build + query, 5 rounds")
    print(f"{'N':>8} {'cell list':>10} {'ADT':>10} {'ADT/cell':>9} {'cKDTree':>10} "
          f"{'cKD/cell':>9} {'pairs/disk':>10}")
    for size in args.sizes:
        n = int(size)
        x, r = dense(n)
        margin = 0.1 * r.min()
        rr = r + 0.5 * margin
        boxes = np.c_[x - rr[:, None], x + rr[:, None]]
        rmax = r.max()

        def cell():
            return disk_pairs_cell_list(x, r, margin)

        def adt():
            return self_pairs(boxes)

        def ckd():
            return cKDTree(x).query_pairs(2 * rmax + margin, output_type="ndarray")

        ref = cell()
        for name, fn in (("ADT", adt), ("cKDTree", ckd)):
            got = filtered(np.asarray(fn(), dtype=np.int64), x, r, margin)
            if not np.array_equal(got, ref):
                raise SystemExit(f"{name} pairs differ from the cell list at N = {n}")
        times = []
        for fn in (cell, adt, ckd):
            fn()
            samples = []
            for _ in range(5):
                t0 = time.perf_counter()
                fn()
                samples.append(time.perf_counter() - t0)
            times.append(statistics.median(samples) / n)
        tc, ta, tk = times
        print(f"{n:>8d} {tc * 1e9:>8.0f}ns {ta * 1e9:>8.0f}ns {ta / tc:>9.2f} "
              f"{tk * 1e9:>8.0f}ns {tk / tc:>9.2f} {ref.shape[0] / n:>10.2f}")


if __name__ == "__main__":
    main()
