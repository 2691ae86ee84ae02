"""The alternating digital tree returns exactly the meeting pairs.

References: the O(N²) numba brute force (``brute_force_pairs``), itself checked against a
dense numpy broadcast; for 1e5 boxes a sort-and-sweep (``naive.sweep_pairs``), checked
against the brute force; all comparisons are exact (integer pair arrays).
"""

from mpi4py import MPI

import numpy as np
import pytest
from naive import sweep_pairs

from masonry_fdem.interactions.search.adt import (
    brute_force_pairs,
    build_adt,
    inflate,
    query_adt,
    self_pairs,
)


def random_boxes(n: int, dim: int = 2, seed: int = 0, size_ratio: float = 100.0) -> np.ndarray:
    """(n, 2 dim) boxes in a cube of side ~n^(1/dim) (a few neighbours each): sizes varying
    by ``size_ratio`` (log-uniform), 10 % zero-size (points), exact duplicates, and boxes
    touching exactly (sharing a face or a corner)."""
    rng = np.random.default_rng(seed)
    side = max(n ** (1.0 / dim), 1.0)
    c = rng.random((n, dim)) * side
    scale = np.exp(rng.random((n, 1)) * np.log(size_ratio)) / np.sqrt(size_ratio)
    h = 0.8 * rng.random((n, dim)) * scale
    h[rng.random(n) < 0.1] = 0.0
    b = np.c_[c - h, c + h]
    if n >= 20:
        b[10:15] = b[:5]  # exact duplicates
        b[15, :dim] = b[16, dim:]  # 15 starts exactly at 16's upper corner: touching
        b[15, dim:] = b[15, :dim] + 0.1
        b[17, :dim] = b[16, dim:]  # 17 is the point at that corner
        b[17, dim:] = b[16, dim:]
    return b


def dense_pairs(boxes: np.ndarray, group=None) -> np.ndarray:
    """All i < j pairs of meeting boxes by a dense numpy broadcast (small n only)."""
    d = boxes.shape[1] // 2
    meet = np.all(boxes[:, None, :d] <= boxes[None, :, d:], axis=2) & np.all(
        boxes[None, :, :d] <= boxes[:, None, d:], axis=2)
    if group is not None:
        meet &= group[:, None] != group[None, :]
    i, j = np.nonzero(np.triu(meet, 1))
    return np.stack([i, j], axis=1).astype(np.int64)


def test_brute_force_reference_is_right():
    for dim in (2, 3):
        boxes = random_boxes(400, dim=dim, seed=dim)
        group = np.arange(400) // 3
        assert np.array_equal(brute_force_pairs(boxes), dense_pairs(boxes))
        assert np.array_equal(brute_force_pairs(boxes, group), dense_pairs(boxes, group))


@pytest.mark.parametrize("n", [0, 1, 2, 10, 1000, 10_000])
@pytest.mark.parametrize("grouped", [False, True])
def test_self_pairs_equal_brute_force(n, grouped):
    boxes = random_boxes(n, seed=n)
    group = np.arange(n) // 4 if grouped else None
    pairs = self_pairs(boxes, group)
    ref = brute_force_pairs(boxes, group)
    assert pairs.dtype == np.int64 and pairs.shape == (len(ref), 2)
    assert np.array_equal(pairs, ref)
    if n >= 20 and not grouped:
        found = {tuple(p) for p in pairs}
        assert {(15, 16), (16, 17), (15, 17)} <= found  # touching counts
        assert all((k, k + 10) in found for k in range(5))  # duplicates


# the ADT is a serial algorithm: under mpirun every rank would repeat the same 1e5-box
# search and its brute-force reference (some 18 s of the suite's budget)
SERIAL = pytest.mark.skipif(MPI.COMM_WORLD.size > 1, reason="one process: a serial "
                            "algorithm, each rank would repeat it (the suite's budget)")


def test_sweep_reference_is_right():
    """The sort-and-sweep reference of the 1e5-box tests equals the brute force."""
    boxes = random_boxes(5000, seed=11, size_ratio=100.0)
    group = np.random.default_rng(2).integers(0, 1000, 5000)
    assert np.array_equal(sweep_pairs(boxes), brute_force_pairs(boxes))
    assert np.array_equal(sweep_pairs(boxes, group), brute_force_pairs(boxes, group))


@pytest.fixture(scope="module")
def boxes_1e5():
    """1e5 boxes, sizes varying 100x, with their pairs by sort-and-sweep (the brute force
    took 18 s of the suite's time)."""
    boxes = random_boxes(100_000, seed=7, size_ratio=100.0)
    return boxes, sweep_pairs(boxes)


@SERIAL
def test_self_pairs_1e5_boxes(boxes_1e5):
    boxes, ref = boxes_1e5
    assert len(ref) > 100_000
    assert np.array_equal(self_pairs(boxes), ref)


@SERIAL
def test_self_pairs_1e5_boxes_grouped(boxes_1e5):
    """Same-group pairs left out: the brute-force set filtered by group."""
    boxes, ref = boxes_1e5
    group = np.random.default_rng(1).integers(0, 20_000, boxes.shape[0])
    keep = group[ref[:, 0]] != group[ref[:, 1]]
    assert 0 < (~keep).sum() < len(ref)
    assert np.array_equal(self_pairs(boxes, group), ref[keep])


@pytest.mark.parametrize("grouped", [False, True])
def test_three_dimensional_boxes(grouped):
    boxes = random_boxes(3000, dim=3, seed=5)
    group = np.arange(3000) % 7 if grouped else None
    ref = brute_force_pairs(boxes, group)
    assert len(ref) > 1000
    assert np.array_equal(self_pairs(boxes, group), ref)


def test_query_other_boxes():
    items = random_boxes(5000, seed=11)
    queries = random_boxes(700, seed=12)
    queries[0] = [-1e9, -1e9, 1e9, 1e9]  # meets everything
    queries[1, :2] = items[3, 2:]  # touches item 3 at a corner
    queries[1, 2:] = items[3, 2:] + 1.0
    qi, it = query_adt(build_adt(items), queries)
    d = 2
    meet = np.all(queries[:, None, :d] <= items[None, :, d:], axis=2) & np.all(
        items[None, :, :d] <= queries[:, None, d:], axis=2)
    ref_q, ref_i = np.nonzero(meet)
    assert np.array_equal(qi, ref_q) and np.array_equal(it, ref_i)
    assert np.count_nonzero(qi == 0) == 5000 and 3 in it[qi == 1]


def test_query_empty_cases():
    empty = np.zeros((0, 4))
    qi, it = query_adt(build_adt(empty), random_boxes(10))
    assert qi.size == 0 and it.size == 0
    qi, it = query_adt(build_adt(random_boxes(10)), empty)
    assert qi.size == 0 and it.size == 0
    assert self_pairs(empty).shape == (0, 2)


def test_just_apart_is_not_touching():
    a = np.array([[0.0, 0.0, 1.0, 1.0], [np.nextafter(1.0, 2.0), 0.0, 2.0, 1.0],
                  [1.0, 1.0, 1.0, 1.0]])
    assert np.array_equal(self_pairs(a), [[0, 2]])  # box 1 starts one ulp right of 1.0
    a[1, 0] = 1.0
    assert np.array_equal(self_pairs(a), [[0, 1], [0, 2], [1, 2]])


@pytest.mark.parametrize("n", [1000, 100_000])
def test_tree_depth_is_logarithmic(n):
    """Depth <= c log2 N with c = 3 (measured ~2.0 for small boxes, where every other
    bisection, along a max coordinate, separates little), also for input sorted along x
    (an ADT is a digital tree: its shape does not depend much on insertion order)."""
    boxes = random_boxes(n, seed=1)
    for b in (boxes, boxes[np.argsort(boxes[:, 0])]):
        tree = build_adt(b)
        assert tree.depth <= 3 * np.log2(n)
        assert np.array_equal(np.sort(tree.item), np.arange(n))
        assert tree.size[0] == n


def test_seeded_insertion_order_gives_same_pairs():
    boxes = random_boxes(2000, seed=4)
    ref = brute_force_pairs(boxes)
    tree = build_adt(boxes, seed=3)
    qi, it = query_adt(tree, boxes)
    keep = qi < it
    assert np.array_equal(np.stack([qi[keep], it[keep]], axis=1), ref)


def test_degenerate_identical_boxes():
    """300 identical boxes (an ADT chain, depth 300): every pair found exactly once."""
    boxes = np.tile([[0.0, 0.0, 1.0, 1.0]], (300, 1))
    pairs = self_pairs(boxes)
    i, j = np.triu_indices(300, 1)
    assert np.array_equal(pairs, np.stack([i, j], axis=1))


def test_inflate_and_errors():
    b = np.array([[0.0, 0.0, 1.0, 1.0]])
    assert np.array_equal(inflate(b, 0.5), [[-0.5, -0.5, 1.5, 1.5]])
    assert np.array_equal(b, [[0.0, 0.0, 1.0, 1.0]])  # not modified in place
    with pytest.raises(ValueError, match="margin"):
        inflate(b, -1.0)
    with pytest.raises(ValueError, match="min > max"):
        build_adt(np.array([[1.0, 0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match="finite"):
        build_adt(np.array([[np.nan, 0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match=r"shape \(n, 2\*dim\)"):
        build_adt(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="group"):
        self_pairs(np.zeros((3, 4)), np.zeros(2))
    with pytest.raises(ValueError, match="columns"):
        query_adt(build_adt(np.zeros((3, 4))), np.zeros((1, 6)))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_cell_grid_flags_every_box_that_meets(seed):
    """The coarse grid the ranks pick their ghost facets with: a box of one set that meets
    (closed) a box of the other is always flagged, however the boxes straddle, touch or
    cover the cells (long thin boxes included); boxes far from all are not."""
    from masonry_fdem.interactions.search import boxes_on_cells, mark_cells

    rng = np.random.default_rng(seed)

    def boxes(n):
        lo = rng.uniform(0.0, 10.0, (n, 2))
        size = rng.exponential(0.2, (n, 2))
        size[: n // 10, 0] = rng.uniform(2.0, 8.0, n // 10)  # long, thin
        b = np.c_[lo, lo + size]
        b[n // 10 : n // 5, 2:] = b[n // 10 : n // 5, :2]  # points
        return b

    a, b = boxes(300), boxes(400)
    b[300:, [0, 2]] += 12.0  # a region of b's own
    b[:20, :2] = a[:20, 2:]  # corners touching exactly
    b[:20, 2:] = b[:20, :2] + 0.1
    lo = np.minimum(a[:, :2].min(axis=0), b[:, :2].min(axis=0))
    hi = np.maximum(a[:, 2:].max(axis=0), b[:, 2:].max(axis=0))
    h = 0.37
    gx, gy = (int(np.ceil(e / h)) for e in hi - lo)
    occ = np.zeros((gy, gx), dtype=np.uint8)
    mark_cells(a, a.shape[0], lo, 1.0 / h, gx, gy, 0.0, occ)
    flag = np.zeros(b.shape[0], dtype=np.bool_)
    boxes_on_cells(b, b.shape[0], lo, 1.0 / h, gx, gy, occ, flag)
    meets = ((b[:, None, :2] <= a[None, :, 2:]) & (a[None, :, :2] <= b[:, None, 2:])).all(
        axis=2).any(axis=1)
    assert meets[:20].all()
    assert flag[meets].all()
    # far boxes: more than a cell's diagonal from every box of a are never flagged
    gap = np.maximum(np.maximum(a[None, :, :2] - b[:, None, 2:],
                                b[:, None, :2] - a[None, :, 2:]), 0.0)
    far = np.sqrt((gap ** 2).sum(axis=2)).min(axis=1) > 2.0 * np.sqrt(2.0) * h
    assert far.any() and not flag[far].any()
