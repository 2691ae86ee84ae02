"""How a quasi-static run ended: one status for every run, and a collapse load only when
the run proved one.

A run that stops because its solver ran out of iterations has found nothing about the
structure: it is *not converged at λ*, and the last load it carried is a lower bound of
the collapse load, never the collapse load itself. Only a traced path that went over its
peak (*peak passed*) or a singular tangent with the load no longer rising (*mechanism*)
gives a collapse load.

Units: load factors are whatever the run scales (a factor on the live loads, or a load
[N] when the live load is a unit force).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

__all__ = ["Status", "RunStatus"]


class Status(str, Enum):
    """The end of a quasi-static run."""

    #: the traced load fell a stated fraction below its maximum (or the path turned back)
    PEAK_PASSED = "peak passed"
    #: the tangent became singular with the load no longer rising
    MECHANISM = "mechanism"
    #: the run reached its displacement limit with the load still rising or level
    DISPLACEMENT_LIMIT = "displacement limit reached"
    #: the run carried the largest load it was asked to (no collapse sought beyond it)
    LOAD_REACHED = "load reached"
    #: the solver found no equilibrium at the next load (or displacement) step
    NOT_CONVERGED = "not converged"

    @property
    def gives_collapse_load(self) -> bool:
        """Whether a run ending so has measured a collapse load."""
        return self in (Status.PEAK_PASSED, Status.MECHANISM)

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class RunStatus:
    """The status of a run and what it says of the load.

    Attributes:
        status: the :class:`Status`.
        load: the last converged load (factor).
        peak: the largest converged load (factor) of the run.
        at: where the run stopped without equilibrium (the load factor, or the
            displacement [m], it was trying to reach); None unless not converged.
        detail: a short reason (e.g. "Newton: 25 iterations, |r|/|f| = 3e-4").
        at_kind: what ``at`` is: "load" (a load factor or load) or "displacement" [m].
    """

    status: Status
    load: float
    peak: float
    at: float | None = None
    detail: str = ""
    at_kind: str = "load"

    @property
    def collapse_load(self) -> float | None:
        """The collapse load (the peak) if the run proved one, else None."""
        return self.peak if self.status.gives_collapse_load else None

    @property
    def lower_bound(self) -> float:
        """A load the structure was shown to carry (the peak of the converged states)."""
        return self.peak

    def describe(self, unit: str = "", scale: float = 1.0, fmt: str = ".4g") -> str:
        """One line for a report, e.g. ``"not converged at 12.5 kN (carried 12.2 kN, a
        lower bound of the collapse load)"``; loads are divided by ``scale``."""

        def q(x: float) -> str:
            return f"{x / scale:{fmt}}{(' ' + unit) if unit else ''}"

        s = self.status
        if s is Status.NOT_CONVERGED:
            if self.at is None or not math.isfinite(self.at):
                where = ""
            elif self.at_kind == "displacement":
                where = f" at displacement {self.at * 1e3:.4g} mm"
            else:
                where = f" at {q(self.at)}"
            text = (f"not converged{where} (carried {q(self.peak)}, a lower bound of the "
                    "collapse load)")
        elif s.gives_collapse_load:
            text = f"{s.value}: collapse load {q(self.peak)}"
        elif s is Status.LOAD_REACHED:
            text = f"load reached: carried {q(self.peak)} without collapse"
        else:
            text = f"{s.value}: carried {q(self.peak)} (a lower bound of the collapse load)"
        return f"{text}; {self.detail}" if self.detail else text
