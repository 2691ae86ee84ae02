"""masonry_fdem: combined finite/discrete element analysis of masonry structures on FEniCSx.

Deformable masonry blocks (bricks, voussoirs) live together in ONE dolfinx mesh and are
moved by an explicit central-difference loop or brought to equilibrium by dynamic
relaxation. Units are SI throughout.

Typical use::

    from masonry_fdem import Material, Model, geometry
    from masonry_fdem.solvers import DynamicRelaxation

    blocks = geometry.build_arch(...)
    model = Model(blocks, {"brick": Material(density=2000.0, E=5e9, nu=0.2)})
"""

from masonry_fdem import _compat  # noqa: F401  (dolfinx_solver before dolfinx)
from masonry_fdem.materials import Hypothesis, Material
from masonry_fdem.model import Model

__version__ = "0.1.0"

__all__ = ["Hypothesis", "Material", "Model", "__version__"]
