"""Input checks shared by every layer: a clear message naming the bad value."""

from __future__ import annotations

import numpy as np

__all__ = ["check_positive"]


def check_positive(name: str, value: float, allow_zero: bool = False,
                   allow_inf: bool = False) -> None:
    """Raise ValueError unless ``value`` is a number > 0 (``>= 0`` with ``allow_zero``),
    finite unless ``allow_inf``."""
    ok = (value >= 0 if allow_zero else value > 0) and (allow_inf or np.isfinite(value))
    if not (np.isscalar(value) and not np.isnan(value) and ok):
        sign = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be {sign}, got {value}")
