"""Broad-phase contact search: the ADT against brute force, scipy cKDTree and a numba
sorted cell list, in the same run.

Facet-like boxes: random short segments in a square whose side is chosen so that each box
meets ~4-8 others, N = 1e3 ... 1e6, once with uniform segment lengths and once with lengths
varying 10x (log-uniform). Every method returns the sorted (i < j) pair array and must
return the same pairs (checked and printed). For each N and method the median time per
facet of the whole search (build + self-pair query + sorted output) is printed, then the
fitted scaling exponent of the ADT and the ratios against the cell list and cKDTree,
beside the goals of the issue.

Run: ``python benchmarks/contact_search.py [--max-n 1e6] [--repeats 5]``.
"""

import argparse
import statistics
import time

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from masonry_fdem.interactions.search import _kernels as _adt_kernels
from masonry_fdem.interactions.search.adt import brute_force_pairs, self_pairs


def segments(n: int, variation: float, seed: int = 0) -> np.ndarray:
    """(n, 4) boxes [m] of random segments of lengths 1 .. ``variation`` (log-uniform),
    in a square sized for ~5 neighbours per box."""
    rng = np.random.default_rng(seed)
    length = np.exp(rng.random(n) * np.log(variation))
    mean_sq = np.mean((length + length.mean()) ** 2)
    side = np.sqrt(n * 0.45 * mean_sq / 6.0)
    c = rng.random((n, 2)) * side
    ang = rng.random(n) * np.pi
    half = 0.5 * length[:, None] * np.c_[np.abs(np.cos(ang)), np.abs(np.sin(ang))]
    return np.c_[c - half, c + half]


def sorted_pairs(pi: np.ndarray, pj: np.ndarray, n: int) -> np.ndarray:
    """(m, 2) lexicographically sorted (min, max) pairs, by the same O(m + n) sort the ADT
    uses, so that every method pays the same for its output."""
    out = np.empty((pi.size, 2), dtype=np.int64)
    _adt_kernels.sort_pairs(pi, pj, np.empty(n + 1, np.int64), np.empty(n, np.int64), out)
    return out


# --- sorted cell list -------------------------------------------------------------------

# half of the 3x3 neighbourhood (the other half is visited from the other side)
_HALF = np.array([[1, 0], [-1, 1], [0, 1], [1, 1]], dtype=np.int64)


@njit(cache=True)
def _bin(boxes, lo0, lo1, h, nx, ny, cell, start, order, sboxes):
    """Counting sort of the box centres into cells of side h; sboxes = boxes[order]."""
    n = boxes.shape[0]
    start[:] = 0
    for i in range(n):
        cx = min(int((0.5 * (boxes[i, 0] + boxes[i, 2]) - lo0) / h), nx - 1)
        cy = min(int((0.5 * (boxes[i, 1] + boxes[i, 3]) - lo1) / h), ny - 1)
        cell[i] = cy * nx + cx
        start[cell[i] + 1] += 1
    for c in range(nx * ny):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    for i in range(n):
        p = fill[cell[i]]
        fill[cell[i]] += 1
        order[p] = i
        for j in range(4):
            sboxes[p, j] = boxes[i, j]


@njit(cache=True)
def _cell_pairs(sboxes, order, start, nx, ny, half, out_i, out_j):
    """Each box against the later boxes of its cell and all boxes of half its neighbours."""
    cap = out_i.size
    cnt = 0
    for cy in range(ny):
        for cx in range(nx):
            c = cy * nx + cx
            for a in range(start[c], start[c + 1]):
                x0, y0, x1, y1 = sboxes[a, 0], sboxes[a, 1], sboxes[a, 2], sboxes[a, 3]
                for s in range(-1, half.shape[0]):
                    if s < 0:
                        b0, b1 = a + 1, start[c + 1]
                    else:
                        ex, ey = cx + half[s, 0], cy + half[s, 1]
                        if ex < 0 or ex >= nx or ey >= ny:
                            continue
                        e = ey * nx + ex
                        b0, b1 = start[e], start[e + 1]
                    for b in range(b0, b1):
                        if (sboxes[b, 0] <= x1 and x0 <= sboxes[b, 2] and sboxes[b, 1] <= y1
                                and y0 <= sboxes[b, 3]):
                            if cnt < cap:
                                out_i[cnt] = order[a]
                                out_j[cnt] = order[b]
                            cnt += 1
    return cnt


def cell_list_pairs(boxes: np.ndarray) -> np.ndarray:
    """Sorted cell list: cells of side = largest box extent, box centres counting-sorted
    by cell (boxes copied in cell order), each cell against itself and 4 of its 8
    neighbours, exact box test."""
    n = boxes.shape[0]
    h = float((boxes[:, 2:] - boxes[:, :2]).max()) * (1 + 1e-12) + 1e-300
    lo0, lo1 = float(boxes[:, 0].min()), float(boxes[:, 1].min())
    nx = int((boxes[:, 2].max() - lo0) / h) + 1
    ny = int((boxes[:, 3].max() - lo1) / h) + 1
    cell = np.empty(n, np.int64)
    start = np.empty(nx * ny + 1, np.int64)
    order = np.empty(n, np.int64)
    sboxes = np.empty((n, 4))
    _bin(boxes, lo0, lo1, h, nx, ny, cell, start, order, sboxes)
    cap = 8 * n + 16
    while True:
        oi = np.empty(cap, np.int64)
        oj = np.empty(cap, np.int64)
        k = _cell_pairs(sboxes, order, start, nx, ny, _HALF, oi, oj)
        if k <= cap:
            break
        cap = k
    return sorted_pairs(oi[:k], oj[:k], n)


# --- scipy cKDTree ----------------------------------------------------------------------


def ckdtree_pairs(boxes: np.ndarray) -> np.ndarray:
    """cKDTree.query_pairs on box centres within twice the largest half-diagonal (no
    meeting pair is farther apart), then the exact box test (numpy)."""
    centre = 0.5 * (boxes[:, :2] + boxes[:, 2:])
    half = 0.5 * (boxes[:, 2:] - boxes[:, :2])
    r = 2.0 * float(np.sqrt((half**2).sum(axis=1)).max())
    cand = cKDTree(centre).query_pairs(r, output_type="ndarray")
    i, j = cand[:, 0], cand[:, 1]
    ok = np.all(boxes[i, :2] <= boxes[j, 2:], axis=1) & np.all(
        boxes[j, :2] <= boxes[i, 2:], axis=1)
    return sorted_pairs(np.ascontiguousarray(i[ok], np.int64),
                        np.ascontiguousarray(j[ok], np.int64), boxes.shape[0])


METHODS = {"ADT": self_pairs, "cell list": cell_list_pairs, "cKDTree": ckdtree_pairs,
           "brute": brute_force_pairs}


def median_time(fn, boxes: np.ndarray, repeats: int) -> tuple[float, np.ndarray]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn(boxes)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def run(variation: float, sizes: list[int], repeats: int) -> None:
    print(f"\n== segment lengths varying {variation:g}x ==")
    print(f"{'N':>8} {'pairs':>8} {'nbrs':>5}" + "".join(f"{m:>11}" for m in METHODS)
          + "   same pairs   [ns per facet, median]")
    rows = {}
    for n in sizes:
        boxes = segments(n, variation, seed=n)
        reps = repeats if n <= 100_000 else max(3, repeats // 2)  # a median of >= 3
        res, ref, same = {}, None, True
        for name, fn in METHODS.items():
            if name == "brute" and n > 10_000:
                continue
            t, pairs = median_time(fn, boxes, reps)
            res[name] = t / n
            if ref is None:
                ref = pairs
            else:
                same &= bool(np.array_equal(ref, pairs))
        rows[n] = res
        print(f"{n:8d} {len(ref):8d} {2 * len(ref) / n:5.1f}" + "".join(
            f"{1e9 * res[m]:11.0f}" if m in res else f"{'-':>11}" for m in METHODS)
            + f"   {same}")
    ns = np.array(sizes, dtype=float)
    total = np.array([rows[n]["ADT"] * n for n in sizes])
    expo = np.polyfit(np.log(ns), np.log(total), 1)[0] if len(ns) > 1 else float("nan")
    print(f"ADT scaling exponent (log-log slope of total time, N = {sizes[0]:.0e}.."
          f"{sizes[-1]:.0e}): {expo:.3f}   goal <= 1.15: {'met' if expo <= 1.15 else 'NOT met'}")
    for n in sizes:
        print(f"N = {n:8d}: ADT / cell list = {rows[n]['ADT'] / rows[n]['cell list']:5.2f}, "
              f"ADT / cKDTree = {rows[n]['ADT'] / rows[n]['cKDTree']:5.2f}")
    goal = 3.0 if variation == 1.0 else 1.5
    for n in (100_000, 1_000_000):
        if n in rows:
            r = rows[n]["ADT"] / rows[n]["cell list"]
            print(f"goal: ADT within {goal}x of the cell list at N = {n:.0e} -> {r:.2f}x: "
                  f"{'met' if r <= goal else 'NOT met'}")
    slower = [n for n in sizes if rows[n]["ADT"] > rows[n]["cKDTree"]]
    print("goal: ADT never slower than cKDTree -> "
          + ("met" if not slower else f"NOT met at N = {slower}"))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-n", type=float, default=1e6)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    sizes = [n for n in (1_000, 10_000, 100_000, 1_000_000) if n <= args.max_n]
    warm = segments(300, 10.0)
    for fn in METHODS.values():  # compile (or load the numba cache) before timing
        fn(warm)
    t0 = time.perf_counter()
    for variation in (1.0, 10.0):
        run(variation, sizes, args.repeats)
    print(f"\ntotal benchmark time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
