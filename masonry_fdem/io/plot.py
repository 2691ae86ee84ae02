"""PNG pictures of the deformed blocks coloured by a field (matplotlib, rank 0)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_blocks", "save_load_curve"]


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
            node_values, label = np.linalg.norm(u, axis=1), "|u| [m]"
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
    fig, ax = plt.subplots(figsize=(8, 6), dpi=120)
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
            ax.legend(loc="upper right", fontsize=7)
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
    fig.colorbar(pc, ax=ax, label=label, shrink=0.8)
    if anchors is not None:
        ok = ~arupt
        lc = LineCollection(aseg[ok], array=aforce[ok] / 1e3, cmap="plasma", linewidths=2.5)
        ax.add_collection(lc)
        if arupt.any():
            ax.add_collection(LineCollection(aseg[arupt], colors="0.5", linewidths=1.5,
                                             linestyles="dashed"))
        fig.colorbar(lc, ax=ax, label="anchor force [kN]", shrink=0.8, pad=0.02)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title or f"deformed x{scale:g}")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, bbox_inches="tight")
    plt.close(fig)
    return path


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
