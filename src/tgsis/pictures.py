"""Pictures of surfaces: PNG scenes and GIF animations, drawn with matplotlib (no display, no database).

matplotlib is the optional extra ``pictures`` (``pip install 'tgsis[pictures]'``),
imported when a picture is drawn: without it, :func:`scene`, :func:`section`
and :func:`animation` raise :class:`~tgsis.errors.InstallationError` naming it.

What a geologist wants to see rather than read: several surfaces in one scene
("the structure at t"), axes labelled with their units, equal aspect (with an
optional vertical exaggeration, said in the title), the time and its unit in
the title, and colour by displacement from a reference shape (the same
surface at t0, or in another version) rather than by height.

>>> from tgsis import pictures                          # doctest: +SKIP
>>> pictures.scene([flat, dome], "dome.png", title="salt dome at t = 1 Myr")
>>> pictures.animation(frames, "dome.gif", reference=frames[0][1], time_unit="Myr")
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from tgsis._optional import require
from tgsis.errors import InvalidInputError
from tgsis.mesh import Surface

__all__ = ["displacement", "scene", "section", "animation", "conflict_overlay"]

FloatArray = npt.NDArray[np.float64]


def displacement(surface: Surface, reference: Surface) -> FloatArray:
    """Distance of each vertex from the same vertex of ``reference``.

    Parameters
    ----------
    surface, reference : Surface
        The same vertices (count and order: two states of one topology period,
        or two versions compared vertex by vertex).

    Returns
    -------
    (n,) float64
    """
    if surface.vertices.shape != reference.vertices.shape:
        raise InvalidInputError(
            f"a displacement needs the same vertices: {surface.vertices.shape[0]} against "
            f"{reference.vertices.shape[0]} in the reference",
            hint="colour by displacement from a state of the same topology period",
        )
    return np.asarray(np.linalg.norm(surface.vertices - reference.vertices, axis=1), dtype=np.float64)


def _axes(figure: Any, bounds: FloatArray, units: Sequence[str], exaggeration: float) -> Any:
    ax = figure.add_subplot(projection="3d")
    span = np.maximum(bounds[1] - bounds[0], 1e-9)
    # a flat extent (a horizontal surface) gets a margin: equal limits make no axis
    pad = np.where(bounds[1] - bounds[0] > 0, 0.0, 0.5 * max(float(span.max()), 1.0) * 1e-3)
    ax.set_xlim(bounds[0, 0] - pad[0], bounds[1, 0] + pad[0])
    ax.set_ylim(bounds[0, 1] - pad[1], bounds[1, 1] + pad[1])
    ax.set_zlim(bounds[0, 2] - pad[2], bounds[1, 2] + pad[2])
    ax.set_box_aspect((span[0], span[1], span[2] * exaggeration))  # equal aspect, z exaggerated on request
    for set_label, axis, unit in zip((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel), "xyz", units):
        set_label(f"{axis} ({unit})" if unit else axis, labelpad=8)
    from matplotlib.ticker import MaxNLocator

    ax.zaxis.set_major_locator(MaxNLocator(max(2, min(5, int(1 + 6 * span[2] * exaggeration / span.max())))))
    return ax


def _bounds(surfaces: Sequence[Surface]) -> FloatArray:
    points = np.concatenate([s.vertices for s in surfaces if s.n_vertices])
    return np.stack([points.min(axis=0), points.max(axis=0)])


def _draw(ax: Any, surfaces: Sequence[Surface], colours: Sequence[FloatArray | None], vmax: float) -> Any:
    """Draw each surface: by its per-vertex values (one shared scale), or else in a colour of its own, named in a legend."""
    from matplotlib import cm, colors
    from matplotlib.patches import Patch

    norm = colors.Normalize(vmin=0.0, vmax=vmax if vmax > 0 else 1.0)
    mappable = cm.ScalarMappable(norm=norm, cmap="viridis")
    palette = ("0.7", "tab:orange", "tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink")
    legend = []
    for i, (surface, values) in enumerate(zip(surfaces, colours)):
        if not surface.n_vertices or not len(surface.cells):
            continue
        v, tri = surface.vertices, surface.cells
        tint = palette[i % len(palette)]
        collection = ax.plot_trisurf(
            v[:, 0],
            v[:, 1],
            v[:, 2],
            triangles=tri,
            linewidth=0.1,
            edgecolor="0.3",
            color=tint,
            shade=values is None,
            alpha=1.0,
        )
        if values is not None:
            collection.set_array(values[tri].mean(axis=1))  # a face takes the mean of its vertices
            collection.set_cmap("viridis")
            collection.set_norm(norm)
        elif len(surfaces) > 1:
            legend.append(Patch(color=tint, label=surface.name or f"surface {i + 1}"))
    if legend:
        ax.legend(handles=legend, loc="upper left", fontsize="small")
    return mappable


def _title(title: str, exaggeration: float) -> str:
    return title + (f" (vertical exaggeration ×{exaggeration:g})" if exaggeration != 1.0 else "")


def scene(
    surfaces: Sequence[Surface],
    path: str | Path,
    *,
    title: str,
    colour: Sequence[FloatArray | None] | None = None,
    colour_label: str = "displacement (m)",
    units: Sequence[str] = ("m", "m", "m"),
    exaggeration: float = 1.0,
    size: tuple[float, float] = (8.0, 6.0),
    dpi: int = 100,
    boxes: Sequence[tuple[npt.ArrayLike, str, str]] = (),
    view: tuple[float, float] | None = None,
) -> Path:
    """Write a PNG of several surfaces in one scene.

    Parameters
    ----------
    surfaces : sequence of Surface
    path : str or path-like
        The ``.png`` written (its folder is created).
    title : str
        Put the time and its unit in it ("... at t = 2.5 Myr").
    colour : sequence of ((n_i,) float64 or None), optional
        Per surface, a value per vertex (e.g. :func:`displacement`), drawn on
        one colour scale with a colour bar; None draws that surface in grey.
    units : three str
        Units of x, y and z for the axis labels.
    exaggeration : float
        Vertical exaggeration (said in the title).
    boxes : sequence of (bounds, label, colour)
        Boxes drawn as wire frames with their label (e.g. the regions of a
        merge): ``bounds`` (2, 3) ``[[xmin, ymin, zmin], [xmax, ymax, zmax]]``
        (z up), ``colour`` a matplotlib colour.
    view : (elevation, azimuth), optional
        Where the eye is, in degrees (matplotlib's ``view_init``: azimuth
        from +x towards +y); default matplotlib's (30, -60).
    """
    require("matplotlib", "tgsis.pictures")
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    from tgsis._zpositive import elevation

    surfaces = [elevation(s) for s in surfaces]  # a picture has no z convention: z up (a Depth mesh negated)
    shown = [s for s in surfaces if s.n_vertices]
    if not shown:
        raise InvalidInputError("nothing to draw: every surface is empty")
    colours = list(colour) if colour is not None else [None] * len(surfaces)
    if len(colours) != len(surfaces):
        raise InvalidInputError(f"{len(colours)} colourings for {len(surfaces)} surfaces")
    frames = [(_box_bounds(b, label), label, tint) for b, label, tint in boxes]
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    figure = plt.figure(figsize=size, dpi=dpi)
    try:
        ax = _axes(figure, _bounds(shown), units, exaggeration)
        vmax = max((float(np.nanmax(c)) for c in colours if c is not None and len(c)), default=0.0)
        mappable = _draw(ax, surfaces, colours, vmax)
        for bounds, label, tint in frames:
            _wire_box(ax, bounds, label, tint)
        if view is not None:
            ax.view_init(elev=view[0], azim=view[1])
        if any(c is not None for c in colours):
            figure.colorbar(mappable, ax=ax, shrink=0.6, pad=0.12, label=colour_label)
        ax.set_title(_title(title, exaggeration))
        figure.savefig(target)
    finally:
        plt.close(figure)
    return target


def _box_bounds(bounds: npt.ArrayLike, label: str) -> FloatArray:
    try:
        box = np.asarray(bounds, dtype=np.float64)
    except (TypeError, ValueError):  # ragged or not numbers
        box = np.full((0,), np.nan)
    if box.shape != (2, 3) or not np.all(np.isfinite(box)) or np.any(box[0] > box[1]):
        shown = box.tolist() if box.size else bounds
        raise InvalidInputError(
            f"the box {label!r} is not [[xmin, ymin, zmin], [xmax, ymax, zmax]] (finite, min <= max): {shown}"
        )
    return box


def _wire_box(ax: Any, box: FloatArray, label: str, colour: str) -> None:
    """The 12 edges of an axis-aligned box, and its label at its top corner."""
    corners = np.array([[box[(i >> a) & 1, a] for a in range(3)] for i in range(8)])
    for i in range(8):
        for a in range(3):
            j = i | (1 << a)
            if j != i:
                ax.plot(*corners[[i, j]].T, color=colour, linewidth=1.2, zorder=10)
    ax.text(*box[1], label, color=colour, fontsize="small", zorder=11)


def _cut(surface: Surface, y: float) -> FloatArray:
    """(k, 2, 2) float64: the segments (x, z) where the plane of constant ``y`` cuts the surface's triangles."""
    v, tri = surface.vertices, surface.cells
    d = v[tri, 1] - y  # (m, 3) signed distances
    segments = []
    for i, j in ((0, 1), (1, 2), (2, 0)):
        crossing = (d[:, i] <= 0) != (d[:, j] <= 0)
        w = np.where(crossing, d[:, i] / np.where(crossing, d[:, i] - d[:, j], 1.0), np.nan)
        a, b = v[tri[:, i]], v[tri[:, j]]
        segments.append(np.where(crossing[:, None], a + w[:, None] * (b - a), np.nan)[:, [0, 2]])
    points = np.stack(segments, axis=1)  # (m, 3 edges, 2): two of them cross
    keep = np.isfinite(points[:, :, 0]).sum(axis=1) == 2
    pairs = points[keep][np.isfinite(points[keep][:, :, 0])].reshape(-1, 2, 2)
    return np.asarray(pairs, dtype=np.float64)


def section(
    surfaces: Sequence[Surface],
    path: str | Path,
    *,
    y: float,
    title: str,
    units: Sequence[str] = ("m", "m"),
    exaggeration: float = 1.0,
    size: tuple[float, float] = (9.0, 4.0),
    dpi: int = 100,
) -> Path:
    """Write a PNG of a vertical cross-section: where the plane of constant ``y`` cuts each surface, in x and z.

    Parameters
    ----------
    surfaces : sequence of Surface
        Each drawn as the lines where the plane cuts its triangles, in a colour of its own, named in a legend.
    y : float
        The section's position.
    units : two str
        Units of x and z.
    exaggeration : float
        Vertical exaggeration (the aspect ratio of the axes; said in the title).
    """
    require("matplotlib", "tgsis.pictures")
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt
    from matplotlib.collections import LineCollection

    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    palette = ("0.4", "tab:orange", "tab:blue", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink")
    figure, ax = plt.subplots(figsize=size, dpi=dpi)
    try:
        drawn = 0
        for i, surface in enumerate(surfaces):
            if not surface.n_vertices or not len(surface.cells):
                continue
            cut = _cut(surface, y)
            if len(cut):
                ax.add_collection(
                    LineCollection(
                        list(cut),
                        colors=palette[i % len(palette)],
                        linewidths=1.5,
                        label=surface.name or f"surface {i + 1}",
                    )
                )
                drawn += 1
        if not drawn:
            raise InvalidInputError(f"the section at y = {y:g} cuts none of the surfaces")
        ax.autoscale()
        ax.set_aspect(exaggeration)
        ax.set_xlabel(f"x ({units[0]})" if units[0] else "x")
        ax.set_ylabel(f"z ({units[1]})" if units[1] else "z")
        ax.legend(loc="best", fontsize="small")
        ax.set_title(_title(f"{title}, section at y = {y:g}{' ' + units[0] if units[0] else ''}", exaggeration))
        figure.tight_layout()
        figure.savefig(target)
    finally:
        plt.close(figure)
    return target


def animation(
    frames: Sequence[tuple[float, Sequence[Surface]]],
    path: str | Path,
    *,
    title: str,
    time_unit: str = "",
    reference: Sequence[Surface] | None = None,
    colour_label: str = "displacement (m)",
    units: Sequence[str] = ("m", "m", "m"),
    exaggeration: float = 1.0,
    fps: int = 4,
    size: tuple[float, float] = (6.4, 4.8),
    dpi: int = 80,
) -> Path:
    """Write a GIF of surfaces through time, the same axes and colour scale in every frame.

    Parameters
    ----------
    frames : sequence of (t, surfaces)
        The scene at each time (the SQL snapshot, for instance).
    path : str or path-like
        The ``.gif`` written.
    title : str
        Each frame's title is ``"<title> at t = <t> <time_unit>"``.
    reference : sequence of Surface, optional
        Colour each surface by its displacement from the reference surface at
        the same place in the scene (same vertices); default: grey.
    """
    require("matplotlib", "tgsis.pictures")
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import animation as mpl_animation
    from matplotlib import pyplot as plt

    if not frames:
        raise InvalidInputError("an animation needs at least one frame")
    shown = [s for _, scene_surfaces in frames for s in scene_surfaces if s.n_vertices]
    if not shown:
        raise InvalidInputError("nothing to draw: every frame is empty")
    bounds = _bounds(shown)

    def colours(scene_surfaces: Sequence[Surface]) -> list[FloatArray | None]:
        if reference is None:
            return [None] * len(scene_surfaces)
        return [
            displacement(s, r) if s.n_vertices and s.vertices.shape == r.vertices.shape else None
            for s, r in zip(scene_surfaces, reference)
        ]

    vmax = max((float(np.nanmax(c)) for _, s in frames for c in colours(s) if c is not None and len(c)), default=0.0)
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    figure = plt.figure(figsize=size, dpi=dpi)
    try:

        def draw(i: int) -> list[Any]:
            figure.clear()
            ax = _axes(figure, bounds, units, exaggeration)
            t, scene_surfaces = frames[i]
            mappable = _draw(ax, scene_surfaces, colours(scene_surfaces), vmax)
            if reference is not None:
                figure.colorbar(mappable, ax=ax, shrink=0.6, pad=0.12, label=colour_label)
            ax.set_title(_title(f"{title} at t = {t:g}{' ' + time_unit if time_unit else ''}", exaggeration))
            return []

        movie = mpl_animation.FuncAnimation(figure, draw, frames=len(frames), blit=False)
        movie.save(str(target), writer=mpl_animation.PillowWriter(fps=fps))
    finally:
        plt.close(figure)
    return target


#: colours of the conflict overlay: the base, each side's edits, unsolved conflict regions, solved ones
OVERLAY_COLOURS = {
    "base": "#b0b0b0",
    "parent": "#1f5fd0",
    "child": "#f08010",
    "conflict": "#e00000",
    "solved": "#8a2be2",
}
#: conflicting regions named one by one in the legend (the others counted in one entry)
_LEGEND_REGIONS = 12


def _overlay_legend(merge: Any, solutions: Mapping[int, str] | None) -> list[tuple[str, str, Literal["-", "--"]]]:
    """The overlay's legend: (label, colour, line style), the conflicting regions with their solutions last.

    Raises
    ------
    InvalidInputError
        A solution that does not fit its region (:func:`tgsis.view.regions.region_state`).
    """
    from tgsis.view.regions import region_state

    solutions = dict(solutions or {})
    unknown = sorted(set(solutions) - {r.index for r in merge.regions})
    if unknown:
        raise InvalidInputError(f"a solution for region {unknown[0]}, which this merge does not have")
    states = {r.index: region_state(r, solutions.get(r.index)) for r in merge.regions}
    entries: list[tuple[str, str, Literal["-", "--"]]] = [
        ("base", OVERLAY_COLOURS["base"], "-"),
        ("parent's edits", OVERLAY_COLOURS["parent"], "-"),
        ("child's edits", OVERLAY_COLOURS["child"], "-"),
    ]
    if any(not r.conflict for r in merge.regions):
        entries.append(("merges by itself", "tab:green", "--"))
    conflicts = [r for r in merge.regions if r.conflict]
    for r in conflicts[:_LEGEND_REGIONS]:
        state = states[r.index]
        if state == "unsolved":
            entries.append((f"region {r.index}: conflict, unsolved", OVERLAY_COLOURS["conflict"], "-"))
        else:
            solution = state.removeprefix("solved-")
            entries.append((f"region {r.index}: conflict, solved with {solution}", OVERLAY_COLOURS["solved"], "-"))
    rest = conflicts[_LEGEND_REGIONS:]
    if rest:
        open_ = sum(states[r.index] == "unsolved" for r in rest)
        entries.append(
            (
                f"{len(rest)} more conflicts: {open_} unsolved, {len(rest) - open_} solved",
                OVERLAY_COLOURS["conflict"] if open_ else OVERLAY_COLOURS["solved"],
                "-",
            )
        )
    return entries


def _cells_touching(mesh: Any, vertex_ids: npt.NDArray[np.int64], cell_ids: npt.NDArray[np.int64]) -> Any:
    """Indices of ``mesh``'s cells with a changed id or on a changed vertex (ids from ``vrtxid`` and the cell key)."""
    vids = np.asarray(mesh.vertex_properties["vrtxid"], dtype=np.int64)
    cids = _cell_ids(mesh)
    on_vertex = np.isin(vids, vertex_ids)
    touched = np.isin(cids, cell_ids)
    if len(mesh.cells):
        touched |= on_vertex[mesh.cells].any(axis=1)
    return touched, on_vertex


def _cell_ids(mesh: Any) -> npt.NDArray[np.int64]:
    key = next(n for n in ("trglid", "segid", "pointid", "tetraid", "cellid") if n in mesh.cell_properties)
    return np.asarray(mesh.cell_properties[key], dtype=np.int64)


def _plan(ax: Any, mesh: Any, cells: Any, colour: str, *, fill: bool, width: float, z: int, style: str = "-") -> None:
    """Draw cells of ``mesh`` in map view (x, y): triangles filled, segments and tetrahedra by edges, points."""
    from matplotlib.collections import LineCollection, PolyCollection

    v = mesh.vertices[:, :2]
    chosen = mesh.cells[cells]
    if not len(chosen):
        return
    k = chosen.shape[1]
    if k == 1:
        ax.scatter(
            v[chosen[:, 0], 0],
            v[chosen[:, 0], 1],
            s=6 * width,
            color=colour,
            zorder=z,
            marker="x" if style != "-" else "o",
        )
    elif k == 3 and fill:
        ax.add_collection(PolyCollection(v[chosen], facecolors=colour, edgecolors="white", linewidths=width, zorder=z))
    else:
        pairs = [(a, b) for a in range(k) for b in range(a + 1, k)] if k > 2 else [(0, 1)]
        edges = np.concatenate([chosen[:, [a, b]] for a, b in pairs])
        ax.add_collection(LineCollection(v[edges], colors=colour, linewidths=width, linestyles=style, zorder=z))


def conflict_overlay(
    merge: Any,
    base: Any,
    parent: Any,
    child: Any,
    path: str | Path,
    *,
    title: str = "",
    dpi: int = 110,
    solutions: Mapping[int, str] | None = None,
) -> Path:
    """A map view (x, y) of a three-way merge: base grey, parent's edits blue, child's orange, regions boxed.

    Parameters
    ----------
    merge : tgsis.MeshMerge
        Its ``regions`` give the changed ids and the boxes (unsolved conflicts red, solved ones violet,
        regions that merge by themselves dashed green).
    base, parent, child : tgsis.Mesh
        The three states as :func:`tgsis.export_conflict` builds them (vertex property ``vrtxid``, the stored
        cell ids as a cell property); the sides' changed cells (and those on a changed vertex) are drawn as
        that side has them, their vertices as dots.
    path : path
        The PNG written.
    solutions : mapping of int to str, optional
        The solution recorded for a conflicting region (by index): ``unsolved`` (the default), ``parent``,
        ``child``, ``base``, ``average`` or ``manual``. The legend names each conflicting region with its
        solution (the first 12; the others counted), and each box is labelled with it.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    InvalidInputError
        A solution for a region that merges by itself, or an unknown one.
    """
    legend = _overlay_legend(merge, solutions)
    solved = {i: s for i, s in (solutions or {}).items() if s not in ("unsolved", "automatic")}
    require("matplotlib", "tgsis.pictures")
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Rectangle

    figure, ax = plt.subplots(figsize=(9, 7))
    try:
        _plan(ax, base, np.ones(len(base.cells), dtype=bool), OVERLAY_COLOURS["base"], fill=True, width=0.3, z=1)
        for side, mesh, alpha_z in (("parent", parent, 2), ("child", child, 3)):
            vids = np.concatenate([getattr(r, f"{side}_vertex_ids") for r in merge.regions] or [np.empty(0, np.int64)])
            cids = np.concatenate([getattr(r, f"{side}_cell_ids") for r in merge.regions] or [np.empty(0, np.int64)])
            cells, on_vertex = _cells_touching(mesh, vids, cids)
            _plan(ax, mesh, cells, OVERLAY_COLOURS[side], fill=False, width=1.6, z=alpha_z)
            moved = mesh.vertices[on_vertex]
            ax.scatter(moved[:, 0], moved[:, 1], s=10, color=OVERLAY_COLOURS[side], zorder=alpha_z + 2)
            # what the side removed: the base's cells of changed ids the side no longer has, dotted
            gone, _ = _cells_touching(base, np.empty(0, np.int64), np.setdiff1d(cids, _cell_ids(mesh)))
            _plan(ax, base, gone, OVERLAY_COLOURS[side], fill=False, width=1.0, z=alpha_z, style=":")
        for r in merge.regions:
            (x0, y0, _), (x1, y1, _) = np.asarray(r.bounds)
            box = OVERLAY_COLOURS["solved" if r.index in solved else "conflict"] if r.conflict else "tab:green"
            ax.add_patch(
                Rectangle(
                    (x0, y0),
                    x1 - x0,
                    y1 - y0,
                    fill=False,
                    edgecolor=box,
                    linestyle="-" if r.conflict else "--",
                    linewidth=2.0 if r.conflict else 1.0,
                    zorder=6,
                )
            )
            said = f": {solved.get(r.index, 'unsolved')}" if r.conflict else ""
            ax.annotate(f"region {r.index}{said}", (x0, y1), fontsize="small", zorder=7)
        everything = np.concatenate([m.vertices[:, :2] for m in (base, parent, child) if len(m.vertices)])
        low, high = everything.min(axis=0), everything.max(axis=0)
        pad = 0.03 * max(float((high - low).max()), 1.0)
        ax.set_xlim(low[0] - pad, high[0] + pad)
        ax.set_ylim(low[1] - pad, high[1] + pad)
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.legend(
            handles=[Line2D([], [], color=colour, linestyle=style, label=label) for label, colour, style in legend],
            loc="upper left",
            bbox_to_anchor=(1.01, 1.0),
            fontsize="small",
        )
        if title:
            ax.set_title(title)
        figure.savefig(path, dpi=dpi, bbox_inches="tight")
    finally:
        plt.close(figure)
    return Path(path)
