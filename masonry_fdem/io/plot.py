"""PNG pictures of the deformed blocks coloured by a field (matplotlib, rank 0)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["label_points", "plot_blocks", "save_load_curve"]


def _von_mises(sig: np.ndarray) -> np.ndarray:
    sxx, sxy, syy = sig[:, 0], sig[:, 1], sig[:, 3]
    return np.sqrt(sxx**2 - sxx * syy + syy**2 + 3.0 * sxy**2)


def plot_blocks(
    model,
    path: str | Path,
    *,
    field: str | np.ndarray = "displacement",
    scale: float = 1.0,
    title: str | None = None,
    cmap: str = "viridis",
    show_edges: bool = False,
    joints=None,
    disks=None,
    anchors=None,
    clim: tuple[float, float] | None = None,
    loads: np.ndarray | None = None,
    load_label: str = "",
    hinges: np.ndarray | None = None,
    hinge_labels: list[str] | None = None,
    hinge_sides: list[float] | None = None,
    hide: np.ndarray | None = None,
) -> Path | None:
    """Draw the blocks in their deformed position, coloured by a field (collective).

    Args:
        model: the model.
        path: PNG file to write (rank 0).
        field: "displacement" (magnitude, nodal), "von_mises" (Cauchy stress, per cell),
            "sigma_xx", "sigma_yy", "sigma_xy" (a Cauchy stress component, per cell),
            "block" (block id), or an array over the BlockMesh nodes or cells.
        scale: displacement magnification for drawing.
        title: picture title.
        cmap: matplotlib colour map.
        show_edges: draw the triangle edges.
        joints: the model's :class:`~masonry_fdem.interactions.Joints`: joints that are not
            intact are drawn over the blocks, coloured by state (softening, open, sliding,
            crushed) — the crack pattern.
        disks: a :class:`~masonry_fdem.interactions.disks.Disks` set, drawn as grey circles with a
            radius line showing their rotation.
        anchors: the :class:`~masonry_fdem.interactions.anchors.Anchors`, drawn as thick lines
            coloured by their axial force per bar [N] (second colour bar); ruptured bar
            elements are drawn dashed in grey.
        clim: (low, high) of the colour scale (default: the field's range).
        loads: ``(k, 2)`` points [m] (undeformed) where a vertical load acts downwards:
            an arrow onto each, at its deformed place, labelled ``load_label``.
        hinges: ``(k, 2)`` points [m] (undeformed) of hinges, circled at their deformed
            place, with ``hinge_labels`` (e.g. the order of opening) beside them: away
            from the middle of the drawing's base, or towards it where ``hinge_sides``
            is negative (a hinge on an arch's intrados).
        hide: ids of blocks whose cells are not coloured (their outlines are drawn): bodies
            that overlap others in the plane, as a bridge's spandrel walls its fill.

    Returns:
        The path on rank 0, None on other ranks.
    """
    blocks = model.blocks
    u = model.displacement()
    cell_values = None
    node_values = None
    label = ""
    if isinstance(field, str):
        if field == "displacement":
            node_values, label = 1e3 * np.linalg.norm(u, axis=1), "|u| [mm]"
        elif field == "von_mises":
            model.update_stress()
            sig = model.stress.x.array.reshape(-1, 4)
            local = _von_mises(sig[: model.dmesh.cell_input.size])
            parts = model.comm.gather((model.dmesh.cell_input, local), root=0)
            if model.comm.rank == 0:
                cell_values = np.zeros(blocks.n_cells)
                for idx, vals in parts:
                    cell_values[idx] = vals
            label = "von Mises stress [Pa]"
        elif field in ("sigma_xx", "sigma_yy", "sigma_xy"):
            model.update_stress()
            sig = model.stress.x.array.reshape(-1, 4)
            col = {"sigma_xx": 0, "sigma_xy": 1, "sigma_yy": 3}[field]
            local = sig[: model.dmesh.cell_input.size, col].copy()
            parts = model.comm.gather((model.dmesh.cell_input, local), root=0)
            if model.comm.rank == 0:
                cell_values = np.zeros(blocks.n_cells)
                for idx, vals in parts:
                    cell_values[idx] = vals
            label = f"σ_{field[-2:]} [Pa] (Cauchy; compression < 0)"
        elif field == "block":
            cell_values, label = blocks.cell_block.astype(float), "block"
        else:
            raise ValueError(f"unknown field {field!r}")
    else:
        arr = np.asarray(field, dtype=float)
        if arr.shape[0] == blocks.n_nodes:
            node_values = arr
        elif arr.shape[0] == blocks.n_cells:
            cell_values = arr
        else:
            raise ValueError("field array must have one value per node or per cell")
    jseg = jstate = None
    if joints is not None:
        jstate = joints.status()
        jseg = joints.segments(scale)
    if anchors is not None:
        aseg = anchors.segments(scale)
        aforce = anchors.axial_force()
        arupt = anchors.ruptured()
    if model.comm.rank != 0:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation

    xy = blocks.x + scale * u
    tri = Triangulation(xy[:, 0], xy[:, 1], blocks.cells)
    if hide is not None and len(hide):
        masked = np.isin(blocks.cell_block, np.asarray(hide))
        tri.set_mask(masked)
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    fig, ax = plt.subplots(figsize=(8, 6), dpi=120)
    # colour bars as tall (or wide) as the drawing, beside it, never over each other
    divider = make_axes_locatable(ax)
    lim = {} if clim is None else {"vmin": clim[0], "vmax": clim[1]}
    if cell_values is not None:
        pc = ax.tripcolor(tri, facecolors=cell_values, cmap=cmap,
                          edgecolors="k" if show_edges else "none", linewidth=0.1, **lim)
    else:
        pc = ax.tripcolor(tri, node_values, cmap=cmap, shading="gouraud", **lim)
        if show_edges:
            ax.triplot(tri, "k-", lw=0.1)
    seg = xy[blocks.boundary_facets]
    ax.add_collection(LineCollection(seg, colors="k", linewidths=0.4))
    if jseg is not None:
        from masonry_fdem.interactions.joints.joints import JOINT_STATES

        colours = {1: "gold", 2: "red", 3: "blue", 4: "magenta"}
        for code, colour in colours.items():
            sel = jstate == code
            if sel.any():
                ax.add_collection(LineCollection(jseg[sel], colors=colour, linewidths=1.6,
                                                 label=JOINT_STATES[code]))
        if np.any(jstate > 0):
            # below the drawing: neither over the blocks nor over the title
            legend_below(ax, ncol=4, fontsize=8, frameon=False, title="joints",
                         title_fontsize=8)
    if disks is not None:
        from matplotlib.collections import PatchCollection
        from matplotlib.patches import Circle

        circles = [Circle((cx, cy), rr) for (cx, cy), rr in zip(disks.x, disks.r, strict=True)]
        ax.add_collection(PatchCollection(circles, facecolor="0.75", edgecolor="0.3",
                                          linewidth=0.3))
        tip = disks.x + disks.r[:, None] * np.c_[np.cos(disks.theta), np.sin(disks.theta)]
        ax.add_collection(LineCollection(np.stack([disks.x, tip], axis=1), colors="0.3",
                                         linewidths=0.3))
        ax.autoscale_view()
    fig.colorbar(pc, cax=divider.append_axes("right", size="3%", pad=0.1), label=label)
    size = float(np.ptp(xy, axis=0).max()) if xy.size else 1.0
    if loads is not None and len(loads):
        tips = _deformed(blocks.x, xy, np.asarray(loads, dtype=float))
        for x, y in tips:
            ax.annotate("", (x, y), xytext=(x, y + 0.12 * size),
                        arrowprops=dict(arrowstyle="-|>", color="C3", lw=1.8,
                                        mutation_scale=14), zorder=6)
        if load_label:
            x0, y0 = tips.mean(axis=0)
            ax.annotate(load_label, (x0, y0 + 0.12 * size), xytext=(0, 4),
                        textcoords="offset points", ha="center", va="bottom", fontsize=9,
                        color="C3")
        ax.set_ylim(top=max(ax.get_ylim()[1], tips[:, 1].max() + 0.18 * size))
    if hinges is not None and len(hinges):
        at = _deformed(blocks.x, xy, np.asarray(hinges, dtype=float))
        ax.plot(at[:, 0], at[:, 1], "o", ms=9, mfc="none", mec="C3", mew=1.8, zorder=6)
        if hinge_labels:
            # outward from the middle of the drawing's base (an arch's springing line)
            base = np.array([0.5 * (xy[:, 0].min() + xy[:, 0].max()), xy[:, 1].min()])
            sides = np.ones(len(at)) if hinge_sides is None else np.asarray(hinge_sides)
            label_points(ax, at, list(hinge_labels) + [""] * (len(at) - len(hinge_labels)),
                         (at - base) * np.sign(sides)[:, None], 0.06 * size, fontsize=8,
                         color="C3")
    if anchors is not None:
        ok = ~arupt
        lc = LineCollection(aseg[ok], array=aforce[ok] / 1e3, cmap="plasma", linewidths=2.5)
        ax.add_collection(lc)
        if arupt.any():
            ax.add_collection(LineCollection(aseg[arupt], colors="0.5", linewidths=1.5,
                                             linestyles="dashed"))
        fig.colorbar(lc, cax=divider.append_axes("right", size="3%", pad=0.75),
                     label="anchor force [kN]")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"deformed x{scale:g}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


def legend_below(ax, **kw):
    """A legend centred a fixed 34 points under the axes, clear of the tick labels and the
    x label however flat the drawing (a fraction of the axes' height, on a wide bridge's
    short axes, put it over the x label). ``kw``: :meth:`Axes.legend` keywords."""
    from matplotlib.transforms import offset_copy

    below = offset_copy(ax.transAxes, fig=ax.figure, y=-34, units="points")
    return ax.legend(loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below,
                     **kw)


#: at most this many labels in one group's text (the rest counted)
MAX_LABELS = 5


def label_points(ax, points, labels, directions, radius: float, **style) -> None:
    """Label points without the labels running over each other: points closer than
    ``radius`` [m] (chained) share one label, their labels joined by commas; it stands
    beyond the group's outermost point along the group's direction (a unit vector per
    point; the first point's counts), aligned so that the text grows away from the
    points; a group of more than :data:`MAX_LABELS` labels shows its first ones and how
    many more. ``style``: text keywords (fontsize, colour, ...)."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    n = len(pts)
    group = np.arange(n)
    for i in range(n):  # single linkage, union by relabelling (a handful of points)
        for j in range(i + 1, n):
            if np.hypot(*(pts[i] - pts[j])) < radius and group[i] != group[j]:
                group[group == group[j]] = group[i]
    for g in dict.fromkeys(group):
        idx = np.flatnonzero(group == g)
        d = np.asarray(directions[idx[0]], dtype=float)
        d = d / max(float(np.hypot(*d)), 1e-300)
        k = idx[np.argmax(pts[idx] @ d)]
        names = list(dict.fromkeys(str(labels[i]) for i in idx if str(labels[i])))
        if not names:
            continue
        if len(names) > MAX_LABELS:
            # a crowd (the many hinges of a multi-ring arch): the first few, in order if
            # they are numbers, and how many more; a long list ran over the colour bars
            if all(t.isdigit() for t in names):
                names.sort(key=int)
            names = names[:MAX_LABELS - 2] + [f"… +{len(names) - MAX_LABELS + 2}"]
        text = ", ".join(names)
        ha = "left" if d[0] > 0.35 else "right" if d[0] < -0.35 else "center"
        va = "bottom" if d[1] > 0.35 else "top" if d[1] < -0.35 else "center"
        ax.annotate(text, tuple(pts[k]), xytext=tuple(9.0 * d), textcoords="offset points",
                    ha=ha, va=va, zorder=7,
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="none", alpha=0.8),
                    **style)


def _deformed(x: np.ndarray, xy: np.ndarray, points: np.ndarray) -> np.ndarray:
    """The deformed places of points: each moved with the node nearest to it."""
    d = np.linalg.norm(x[None, :, :] - points[:, None, :], axis=2)
    near = np.argmin(d, axis=1)
    return points + (xy[near] - x[near])


def save_load_curve(fig, ax, title: str, path: Path) -> None:
    """Label (load [kN] against the load-line displacement [mm]), grid, legend and save a
    load–displacement plot, then close its figure."""
    import matplotlib.pyplot as plt

    ax.set_xlabel("displacement at the load line [mm]")
    ax.set_ylabel("load [kN]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
