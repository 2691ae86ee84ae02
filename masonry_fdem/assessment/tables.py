"""Reading TOML tables with every problem collected: :class:`Table` checks keys, types
and ranges and records one line per problem, naming the table and key."""

from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Mapping, Sequence
from typing import Any


__all__ = ["REQUIRED", "Table", "show"]

REQUIRED = object()

# ---------------------------------------------------------------------- reading tables
def show(v: Any) -> str:
    return repr(v) if isinstance(v, str) else str(v)


class Table:
    """Typed access to one table; problems go to ``problems``, bad values come back None."""

    def __init__(self, problems: list[str], path: str, data: Any, allowed: Sequence[str]):
        self.problems, self.path = problems, path
        if not isinstance(data, Mapping):
            problems.append(f"{path}: must be a table, got {show(data)}")
            data = {}
        self.data = data
        for key in data:
            if key not in allowed:
                close = difflib.get_close_matches(key, list(allowed), n=1)
                hint = (f"did you mean {close[0]!r}?" if close
                        else "expected one of " + ", ".join(allowed))
                where = f"[{path}]" if path else "the case"
                problems.append(f"unknown key {key!r} in {where} ({hint})")

    def name(self, key: str) -> str:
        return f"{self.path}.{key}" if self.path else key

    def bad(self, key: str, msg: str) -> None:
        self.problems.append(f"{self.name(key)}: {msg}")

    def raw(self, key: str, default: Any) -> Any:
        if key in self.data:
            return self.data[key]
        if default is REQUIRED:
            self.bad(key, "missing (required)")
        return None if default is REQUIRED else default

    def number(self, key: str, default: Any = REQUIRED, *, gt: float | None = None,
               ge: float | None = None, lt: float | None = None,
               le: float | None = None) -> float | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
            self.bad(key, f"must be a finite number, got {show(v)}")
            return None
        for bound, op, ok in ((gt, ">", lambda a, b: a > b), (ge, ">=", lambda a, b: a >= b),
                              (lt, "<", lambda a, b: a < b), (le, "<=", lambda a, b: a <= b)):
            if bound is not None and not ok(v, bound):
                self.bad(key, f"must be {op} {bound:g}, got {v}")
                return None
        return float(v)

    def integer(self, key: str, default: Any = REQUIRED, *, ge: int | None = None) -> int | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, numbers.Integral):
            self.bad(key, f"must be an integer, got {show(v)}")
            return None
        if ge is not None and v < ge:
            self.bad(key, f"must be >= {ge}, got {v}")
            return None
        return int(v)

    def string(self, key: str, default: Any = REQUIRED,
               choices: Sequence[str] | None = None) -> str | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if not isinstance(v, str):
            self.bad(key, f"must be a string, got {show(v)}")
            return None
        if choices is not None and v not in choices:
            self.bad(key, f"must be one of {', '.join(map(repr, choices))}, got {v!r}")
            return None
        return v

    def boolean(self, key: str, default: bool) -> bool | None:
        v = self.raw(key, default)
        if not isinstance(v, bool):
            self.bad(key, f"must be true or false, got {show(v)}")
            return None
        return v

    def numbers(self, key: str, default: Any = REQUIRED) -> tuple[float, ...] | None:
        v = self.raw(key, default)
        if v is None or key not in self.data:
            return v
        if (not isinstance(v, list) or not v or any(
                isinstance(a, bool) or not isinstance(a, numbers.Real) or not math.isfinite(a)
                for a in v)):
            self.bad(key, f"must be a non-empty list of numbers, got {show(v)}")
            return None
        return tuple(float(a) for a in v)

    def table(self, key: str, allowed: Sequence[str], required: bool = False) -> Table | None:
        if key not in self.data:
            if required:
                self.problems.append(f"[{self.name(key)}]: missing table (required)")
            return None
        return Table(self.problems, self.name(key), self.data[key], allowed)

    def tables(self, key: str) -> list[Any]:
        v = self.data.get(key, [])
        if not isinstance(v, list) or not all(isinstance(e, Mapping) for e in v):
            self.problems.append(f"{self.name(key)}: must be a list of tables ([[{key}]])")
            return []
        return v
