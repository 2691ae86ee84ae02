"""The complete state of a model and its interactions for checkpoints (this rank's part).

:func:`model_state` holds the displacement (owned and ghost entries of this rank's
array), the velocity, the committed displacement, the material history (the quadrature
functions of the history laws and the return-mapping state: committed and trial
internal variables, stresses, energies, displacement gradients and the algorithmic
tangent), the rate time step and the damage dissipated. :func:`interactions_state`
holds each interaction's :meth:`state` — or its ``checkpoint_state()`` where it has
one: the contact keeps its candidate pairs, its ghost facets and its rebuild counters
so that a resumed run finds the same neighbours at the same steps — and the joints'
property rows (a friction continuation changes them).

Restoring them into a model and interactions built the same way (same case, same
number of ranks) gives back the same arrays bit for bit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["interactions_state", "model_state", "set_interactions_state", "set_model_state"]


def model_state(model) -> dict:
    """This rank's state of ``model`` (copies)."""
    qs = model.qstate
    st = {
        "u": model.u.x.array.copy(),
        "v": np.array(model.v, copy=True),
        "u_committed": model.u_committed.x.array.copy(),
        "damage_dissipated": float(model._damage_dissipated),
        "t_rate": float(qs.t_rate),
        "history": [fn.x.array.copy() for fn, *_ in qs._history],
    }
    if qs.has_return_mapping:
        st["rm"] = {k: np.array(getattr(qs, k), copy=True)
                    for k in ("s0", "s1", "stress", "energy", "strain", "ct")}
    return st


def set_model_state(model, st: Mapping) -> None:
    """Put a state of :func:`model_state` back in place (arrays written in place)."""
    qs = model.qstate
    if st["u"].shape != model.u.x.array.shape:
        raise ValueError(f"model state: {st['u'].shape[0]} displacement entries, the model "
                         f"has {model.u.x.array.size} on this rank (another mesh or "
                         "partition)")
    model.u.x.array[:] = st["u"]
    model.v[:] = st["v"]
    model.u_committed.x.array[:] = st["u_committed"]
    model._damage_dissipated = float(st["damage_dissipated"])
    qs.t_rate = float(st["t_rate"])
    if len(st["history"]) != len(qs._history):
        raise ValueError("model state: another set of material history functions")
    for (fn, *_), arr in zip(qs._history, st["history"], strict=True):
        fn.x.array[:] = arr
    if qs.has_return_mapping:
        for k, arr in st["rm"].items():
            getattr(qs, k)[...] = arr


def interactions_state(interactions: Sequence) -> list[dict]:
    """Each interaction's complete state, in order."""
    out = []
    for c in interactions:
        own = getattr(c, "checkpoint_state", None)
        st = dict(own() if own is not None else c.state())
        if hasattr(c, "props") and hasattr(c, "seg_key"):  # joints: friction continuation
            st["__props"] = np.array(c.props, copy=True)
        out.append({"type": type(c).__name__, "name": str(c.name), "state": st})
    return out


def set_interactions_state(interactions: Sequence, states: Sequence[Mapping]) -> None:
    """Put states of :func:`interactions_state` back (collective). Interactions with a
    ``set_checkpoint_state`` come last, so that what others tell them on their
    ``set_state`` (the joints tell the contact which pairs they hold) is overwritten by
    their own saved state."""
    if [(type(c).__name__, str(c.name)) for c in interactions] != [
            (s["type"], s["name"]) for s in states]:
        raise ValueError("interaction states: another set of interactions ("
                         + ", ".join(s["name"] for s in states) + " saved)")
    later = []
    for c, s in zip(interactions, states, strict=True):
        st = dict(s["state"])
        props = st.pop("__props", None)
        if props is not None:
            c.props[...] = props
        if hasattr(c, "set_checkpoint_state"):
            later.append((c, st))
        else:
            c.set_state(st)
    for c, st in later:
        c.set_checkpoint_state(st)


def set_solver_sets_state(solver, st: Mapping) -> None:
    """The part of a solver's :meth:`set_checkpoint_state` both solvers share: the model,
    the interactions and the arrays of each dof set (collective)."""
    if len(st["sets"]) != len(solver.sets):
        raise ValueError("the state has another set of dof sets")
    set_model_state(solver.model, st["model"])
    set_interactions_state(solver.interactions, st["interactions"])
    for s, arrs in zip(solver.sets, st["sets"], strict=True):
        for k, a in arrs.items():
            getattr(s, k)[...] = a
