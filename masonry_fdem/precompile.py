"""Compile and cache every numba kernel once, before MPI ranks start.

Run ``python -m masonry_fdem.precompile`` serially (``make`` does) so that ranks of a
parallel run load the cache instead of racing to write it. Each package keeps the list
of its own kernels (its ``precompile()``); this module only calls them.
"""

from __future__ import annotations

__all__ = ["precompile"]


def precompile() -> None:
    """Call each package's kernels once on tiny arrays of the production dtypes."""
    from masonry_fdem import interactions, materials, model, solvers

    for package in (model, materials, interactions, solvers):
        package.precompile()


if __name__ == "__main__":
    precompile()
    print("masonry_fdem: numba kernels compiled and cached")
