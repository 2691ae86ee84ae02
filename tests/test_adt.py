"""The alternating digital tree returns exactly the overlapping pairs."""

import numpy as np
import pytest
from naive import sweep_pairs

from masonry_fdem.contact.adt import brute_force_pairs, build_adt, inflate, query_adt, self_pairs


def random_boxes(n, dim=2, seed=0, size_ratio=100.0):
    """Boxes in a square of side ~sqrt(n) (a few neighbours each): sizes varying by
    ``size_ratio``, 10 % zero-size (points), 5 exact duplicates, some exactly touching."""
    rng = np.random.default_rng(seed)
    side = max(np.sqrt(n), 1.0)
    c = rng.random((n, dim)) * side
    scale = np.exp(rng.random((n, 1)) * np.log(size_ratio)) / np.sqrt(size_ratio)
    h = 0.8 * rng.random((n, dim)) * scale
    h[rng.random(n) < 0.1] = 0.0
    b = np.c_[c - h, c + h]
    if n >= 20:
        b[10:15] = b[:5]  # duplicates
        b[15, :dim] = b[16, dim:]  # 15 starts exactly where 16 ends: touching
        b[15, dim:] = b[15, :dim] + 0.1
    return b


@pytest.mark.parametrize("n", [0, 1, 2, 10, 1000, 10_000])
@pytest.mark.parametrize("grouped", [False, True])
def test_self_pairs_equal_brute_force(n, grouped):
    boxes = random_boxes(n, seed=n)
    group = (np.arange(n) // 4) if grouped else None
    pairs = self_pairs(boxes, group)
    ref = brute_force_pairs(boxes, group)
    ref = ref[np.lexsort((ref[:, 1], ref[:, 0]))]
    assert pairs.shape == ref.shape
    assert np.array_equal(pairs, ref)
    if n >= 20:
        assert (15, 16) in {tuple(p) for p in pairs} or grouped  # touching counts


def test_self_pairs_1e5_boxes_brute_force():
    """1e5 boxes, sizes varying 100x, points, duplicates, touching boxes, same-group pairs
    excluded: exactly the O(N²) brute-force set (about 20 s for the brute force)."""
    boxes = random_boxes(100_000, seed=7, size_ratio=100.0)
    group = np.arange(boxes.shape[0]) // 3
    pairs = self_pairs(boxes, group)
    ref = brute_force_pairs(boxes, group)
    ref = ref[np.lexsort((ref[:, 1], ref[:, 0]))]
    assert len(ref) > 10_000
    assert np.array_equal(pairs, ref)


def test_self_pairs_1e5_uniform_boxes_sweep():
    """1e5 boxes of one size class: against an independent exact sort-and-sweep."""
    boxes = random_boxes(100_000, seed=8, size_ratio=1.0)
    pairs = self_pairs(boxes)
    ref = sweep_pairs(boxes)
    assert len(ref) > 10_000
    assert np.array_equal(pairs, ref)


def test_sweep_reference_agrees_with_brute_force():
    boxes = random_boxes(3000, seed=3)
    ref = brute_force_pairs(boxes)
    assert np.array_equal(sweep_pairs(boxes), ref[np.lexsort((ref[:, 1], ref[:, 0]))])


def test_three_dimensional_boxes():
    boxes = random_boxes(2000, dim=3, seed=5)
    ref = brute_force_pairs(boxes)
    assert len(ref) > 0
    assert np.array_equal(self_pairs(boxes), ref[np.lexsort((ref[:, 1], ref[:, 0]))])


def test_query_other_boxes():
    items = random_boxes(5000, seed=11)
    queries = random_boxes(700, seed=12)
    qi, it = query_adt(build_adt(items), queries)
    d = 2
    hit = np.all(queries[:, None, :d] <= items[None, :, d:], axis=2) & np.all(
        items[None, :, :d] <= queries[:, None, d:], axis=2)
    ref_q, ref_i = np.nonzero(hit)
    assert np.array_equal(qi, ref_q) and np.array_equal(it, ref_i)


def test_tree_depth_is_logarithmic():
    """Random insertion order: depth <= 3 log2 N for these sets (measured ~2.1 log2 N)."""
    for n in (1000, 100_000):
        tree = build_adt(random_boxes(n, seed=1))
        assert tree.depth <= 3 * np.log2(n)


def test_inflate_and_errors():
    b = np.array([[0.0, 0.0, 1.0, 1.0]])
    assert np.array_equal(inflate(b, 0.5), [[-0.5, -0.5, 1.5, 1.5]])
    with pytest.raises(ValueError, match="min > max"):
        build_adt(np.array([[1.0, 0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match="finite"):
        build_adt(np.array([[np.nan, 0.0, 0.0, 1.0]]))
    with pytest.raises(ValueError, match=r"shape \(n, 2\*dim\)"):
        build_adt(np.zeros((3, 3)))


def test_degenerate_identical_boxes():
    """500 identical boxes (a deep, one-sided tree): every pair is found once."""
    boxes = np.tile([[0.0, 0.0, 1.0, 1.0]], (500, 1))
    pairs = self_pairs(boxes)
    assert pairs.shape == (500 * 499 // 2, 2)
    assert np.all(pairs[:, 0] < pairs[:, 1])
    assert len({tuple(p) for p in pairs}) == pairs.shape[0]
