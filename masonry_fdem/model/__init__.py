"""The assembled model: one dolfinx mesh of all blocks, materials, masses, loads and
prescribed motions."""

from masonry_fdem.model.model import Model, Prescription

__all__ = ["Model", "Prescription"]


def precompile() -> None:
    """Compile and cache the model's kernels."""
    from masonry_fdem.model import _kernels

    _kernels.precompile()
