"""Physical and numerical constants (SI units)."""

#: Standard gravity [m/s^2].
G = 9.80665

#: Default safety factor on the critical explicit time step.
DT_SAFETY = 0.9

#: Relative tolerance used to decide that two points coincide (times a model length).
GEOM_TOL = 1e-9
