"""The assembled model: one dolfinx mesh of all blocks, materials, masses, loads and
prescribed motions."""

from masonry_fdem.model.model import Model, Prescription

__all__ = ["Model", "Prescription"]
