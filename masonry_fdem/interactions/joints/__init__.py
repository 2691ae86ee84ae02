"""Bonded mortar joints and unit cracks: a zero-thickness cohesive interface law."""

from masonry_fdem.interactions.joints.joints import JOINT_STATES, JointMaterial, Joints

__all__ = ["JOINT_STATES", "JointMaterial", "Joints"]


def precompile() -> None:
    """Compile and cache the joint kernels."""
    from masonry_fdem.interactions.joints import _kernels

    _kernels.precompile()
