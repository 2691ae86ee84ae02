"""Input checks shared by every layer: a clear message naming the bad value.

Three kinds of check live here:

* hard checks (:func:`check_positive`): a value the mathematics refuses (E <= 0, a
  negative length) is always an error;
* magnitude checks (:func:`check_magnitude`, :func:`magnitude_problem`): a value the
  mathematics accepts but no masonry structure has (a 4000 m span, E = 1 Pa, a density of
  2.2 kg/m³) is an error that names the parameter, its value, the expected unit and range,
  and guesses the slip ("did you give millimetres?"). :data:`PLAUSIBLE` is the one place
  that says what is plausible; the API (``Material``, ``JointMaterial``, ``arch_layout``)
  and the case-file schema (:mod:`masonry_fdem.assessment.schema`) both read it. An
  expert who means an unusual value switches the check off, for some parameters or all,
  with :func:`expert` (in a case file: ``[checks] allow = ["arch.span"]``);
* numerical failures (:class:`NumericalError`, :func:`numerical_failures`): NaN,
  floating-point errors, PETSc and HiGHS failures surfacing in a solve become one sentence
  with the likely cause.

Units are SI: m, Pa, kg/m³, N/m (fracture energies), Pa/m (joint stiffnesses), N.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

import numpy as np

__all__ = ["PLAUSIBLE", "ImplausibleValueError", "NumericalError", "Quantity",
           "check_magnitude", "check_positive", "check_ratio", "expert", "is_allowed",
           "magnitude_problem", "numerical_failures", "ratio_problem"]


def check_positive(name: str, value: float, allow_zero: bool = False,
                   allow_inf: bool = False) -> None:
    """Raise ValueError unless ``value`` is a number > 0 (``>= 0`` with ``allow_zero``),
    finite unless ``allow_inf``."""
    ok = (value >= 0 if allow_zero else value > 0) and (allow_inf or np.isfinite(value))
    if not (np.isscalar(value) and not np.isnan(value) and ok):
        sign = ">= 0" if allow_zero else "> 0"
        raise ValueError(f"{name} must be {sign}, got {value}")


# ---------------------------------------------------------------------- magnitudes
@dataclass(frozen=True)
class Quantity:
    """What is plausible for one kind of input.

    Attributes:
        what: what it is, for the message ("clear span of a masonry arch").
        unit: its SI unit ("m"; "" for a pure number).
        lo, hi: the plausible range, inclusive.
        zero_ok: 0 is a meaningful value outside the range (no tension, no cohesion).
        slips: ``(factor, "name")``: when ``value * factor`` is plausible, the user likely
            gave the value in that unit ("millimetres": factor 1e-3).
    """

    what: str
    unit: str
    lo: float
    hi: float
    zero_ok: bool = False
    slips: tuple[tuple[float, str], ...] = ()

    def guess(self, value: float) -> str:
        """"did you give X?" for the slips that would make ``value`` plausible."""
        names = [n for f, n in self.slips if self.lo <= value * f <= self.hi]
        return f"did you give {names[0]}?" if names else ""  # the likeliest slip first


_MM = ((1e-3, "millimetres"), (1e-2, "centimetres"))
_MPA = ((1e6, "MPa (N/mm²)"), (1e9, "GPa"), (1e3, "kPa"))
_STRENGTH = ((1e6, "MPa (N/mm²)"), (1e3, "kPa"))

#: The plausible range of each kind of input: the one place that defines "plausible".
#: Wide on purpose (lab models to the longest masonry spans, soft fills to steel): a value
#: outside is a slip of units far more often than a structure.
PLAUSIBLE: dict[str, Quantity] = {
    "span": Quantity("clear span of a masonry arch", "m", 0.2, 100.0, slips=_MM),
    "rise": Quantity("rise of a masonry arch", "m", 0.02, 100.0, slips=_MM),
    "ring_thickness": Quantity("ring thickness of a masonry arch", "m", 0.02, 5.0, slips=_MM),
    "length": Quantity("length of a masonry structure's part", "m", 0.005, 200.0, slips=_MM),
    "width": Quantity("out-of-plane width", "m", 0.05, 50.0, slips=_MM),
    "diameter": Quantity("bar diameter", "m", 0.003, 0.1, slips=_MM),
    "E": Quantity("Young's modulus of a block material (soft soil to steel)", "Pa", 1e5,
                  1e12, slips=_MPA),
    "steel_E": Quantity("Young's modulus of a bar (FRP to steel)", "Pa", 1e10, 1e12,
                        slips=_MPA),
    "density": Quantity("mass density (timber to lead)", "kg/m³", 100.0, 12000.0,
                        slips=((1e3, "t/m³ (g/cm³)"), (1e3 / 9.81, "a unit weight in kN/m³"))),
    "ft": Quantity("tensile strength of a joint", "Pa", 1e3, 2e7, zero_ok=True,
                   slips=_STRENGTH),
    "c": Quantity("cohesion", "Pa", 1e3, 2e7, zero_ok=True, slips=_STRENGTH),
    "soil_c": Quantity("cohesion of a soil", "Pa", 10.0, 1e7, zero_ok=True, slips=_STRENGTH),
    "fc": Quantity("compressive strength", "Pa", 1e5, 3e8, slips=_STRENGTH),
    "stress": Quantity("strength of steel or bond", "Pa", 1e5, 5e9, slips=_STRENGTH),
    "tan_phi": Quantity("friction coefficient tan φ (10: sliding practically excluded)", "",
                        0.0, 10.0,
                        slips=((math.pi / 180.0, "the angle φ in degrees (tan φ is wanted)"),)),
    "angle": Quantity("friction or dilatancy angle", "deg", 0.0, 60.0,
                      slips=((180.0 / math.pi, "radians"),)),
    "stiffness": Quantity("joint stiffness", "Pa/m", 1e6, 1e15, slips=((1e9, "N/mm³"),)),
    "Gf": Quantity("fracture energy", "N/m", 1.0, 1e4, zero_ok=True,
                   slips=((1e3, "N/mm"),)),
    "Gfc": Quantity("compressive fracture energy", "N/m", 10.0, 1e6, slips=((1e3, "N/mm"),)),
    "force": Quantity("force on a bar", "N", 0.0, 1e7, zero_ok=True,
                      slips=((1e3, "kN"),)),
}

_ALLOWED: ContextVar[frozenset[str]] = ContextVar("masonry_fdem_checks_allowed",
                                                  default=frozenset())


@contextmanager
def expert(*keys: str) -> Iterator[None]:
    """Switch magnitude checks off inside a ``with`` block: those of the named parameters
    (``"E"``, ``"span"``, a case file's ``"arch.span"``), or all of them with no names.
    Hard checks (E > 0, ...) stay on.

    >>> with expert("E"):
    ...     Material(2000.0, 1.0, 0.2)  # a deliberately soft block
    """
    token = _ALLOWED.set(_ALLOWED.get() | (frozenset(keys) or frozenset({"*"})))
    try:
        yield
    finally:
        _ALLOWED.reset(token)


def is_allowed(*keys: str) -> bool:
    """True if an :func:`expert` block allows any of ``keys`` (or everything)."""
    allowed = _ALLOWED.get()
    return "*" in allowed or any(k in allowed for k in keys)


class ImplausibleValueError(ValueError):
    """A value outside its plausible range (:data:`PLAUSIBLE`); ``key`` names it."""

    def __init__(self, message: str, key: str, value: float):
        super().__init__(message)
        self.key, self.value = key, value


def _fmt(v: float) -> str:
    return f"{v:.4g}"


def magnitude_problem(key: str, value: float, kind: str, *, allow_hint: str | None = None,
                      allow: tuple[str, ...] = ()) -> str | None:
    """The message for ``key = value`` if it is outside :data:`PLAUSIBLE` ``[kind]``, else
    None (also when :func:`expert` or ``allow`` allows ``key``, its last part or ``kind``).

    ``allow_hint`` says how to override (default: the :func:`expert` call)."""
    q = PLAUSIBLE[kind]
    leaf = key.rsplit(".", 1)[-1]
    if value is None or isinstance(value, bool) or not isinstance(value, int | float):
        return None
    if not math.isfinite(value) or (q.zero_ok and value == 0) or q.lo <= value <= q.hi:
        return None
    if is_allowed(key, leaf, kind) or key in allow or "*" in allow:
        return None
    unit = f" {q.unit}" if q.unit else ""
    guess = q.guess(value)
    hint = allow_hint or f"masonry_fdem.checks.expert({leaf!r})"
    zero = "0 or " if q.zero_ok else ""
    return (f"{key} = {_fmt(value)}{unit} is implausible for the {q.what}: expected "
            f"{zero}{_fmt(q.lo)} to {_fmt(q.hi)}{unit}" + (f"; {guess}" if guess else "")
            + f" (if you mean it: {hint})")


def check_magnitude(key: str, value: float, kind: str, owner: str = "") -> None:
    """Raise :class:`ImplausibleValueError` if ``value`` is outside the plausible range of
    ``kind`` (see :func:`magnitude_problem`); ``owner`` prefixes the message."""
    msg = magnitude_problem(key, value, kind)
    if msg:
        raise ImplausibleValueError(f"{owner}: {msg}" if owner else msg, key, value)


def ratio_problem(key: str, value: float, ref: float, lo: float, hi: float, unit: str,
                  ref_text: str, *, allow_hint: str | None = None,
                  allow: tuple[str, ...] = ()) -> str | None:
    """The message if ``value / ref`` is outside ``[lo, hi]`` (a mesh size against the
    block size, a load against the self-weight), else None (or allowed, as in
    :func:`magnitude_problem`)."""
    leaf = key.rsplit(".", 1)[-1]
    if not (ref > 0 and math.isfinite(value)) or lo * ref <= value <= hi * ref:
        return None
    if is_allowed(key, leaf) or key in allow or "*" in allow:
        return None
    hint = allow_hint or f"masonry_fdem.checks.expert({leaf!r})"
    return (f"{key} = {_fmt(value)} {unit} is implausible against {ref_text} "
            f"({_fmt(ref)} {unit}): expected {_fmt(lo * ref)} to {_fmt(hi * ref)} {unit} "
            f"({_fmt(lo)} to {_fmt(hi)} times it) (if you mean it: {hint})")


def check_ratio(key: str, value: float, ref: float, lo: float, hi: float, unit: str,
                ref_text: str, owner: str = "") -> None:
    """Raise :class:`ImplausibleValueError` for :func:`ratio_problem`'s message."""
    msg = ratio_problem(key, value, ref, lo, hi, unit, ref_text)
    if msg:
        raise ImplausibleValueError(f"{owner}: {msg}" if owner else msg, key, value)


# ---------------------------------------------------------------------- numerical failures
class NumericalError(RuntimeError):
    """A solve broke down numerically (NaN, overflow, a PETSc or HiGHS failure); the
    message says where and the likely cause. The original exception is its cause."""


#: the usual causes, for the message
LIKELY_CAUSES = ("input magnitudes far from a masonry structure's (E, density, the span "
                 "in millimetres, a load many times the self-weight), a block left without "
                 "support, or a load step too large for the structure to follow")


def _describe(exc: BaseException) -> str | None:
    """A short name of a numerical failure, None if ``exc`` is none."""
    if isinstance(exc, FloatingPointError):
        return "a floating-point error (NaN or overflow)"
    if isinstance(exc, OverflowError | ZeroDivisionError):
        return "an overflow or a division by zero"
    if isinstance(exc, np.linalg.LinAlgError):
        return "a singular linear system"
    if type(exc).__module__.startswith("petsc4py"):
        return "a PETSc failure"
    return None


def numerical_failures(what: str, causes: str = LIKELY_CAUSES) -> Callable:
    """Decorator: a numerical failure inside the function becomes a
    :class:`NumericalError` "``what`` broke down: <failure> (<original message>); likely
    cause: ``causes``"."""

    def wrap(fn: Callable) -> Callable:
        @functools.wraps(fn)
        def inner(*args, **kwargs):
            try:
                return fn(*args, **kwargs)
            except NumericalError:
                raise
            except Exception as exc:
                kind = _describe(exc)
                if kind is None:
                    raise
                detail = str(exc).strip()
                raise NumericalError(
                    f"{what} broke down: {kind}" + (f" ({detail})" if detail else "")
                    + f"; likely cause: {causes}") from exc

        return inner

    return wrap
