"""PNG previews of an evolving surface at a few instants (``tgsis interpolate --preview DIR``).

Drawn with matplotlib's Agg backend (no display needed): a 3D view of the
surface coloured by height, with the same axes in every frame so that the
frames can be flipped through.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from tgsis._optional import require
from tgsis.temporal import EvolvingSurface

__all__ = ["write_previews"]


def write_previews(
    evolving: EvolvingSurface,
    times: Sequence[float],
    folder: str | Path,
    *,
    stem: str = "frame",
    max_triangles: int = 60_000,
) -> list[Path]:
    """Write ``<stem>_<i>.png`` in ``folder`` (created) for each time; returns the paths.

    Parameters
    ----------
    evolving : EvolvingSurface
    times : sequence of float
    folder : str or path-like
    stem : str
    max_triangles : int
        Larger meshes are drawn with an even subset of their triangles (a preview, not a rendering).
    """
    require("matplotlib", "tgsis interpolate --preview (tgsis.interpolation.preview)")
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib import pyplot as plt

    target = Path(folder)
    target.mkdir(parents=True, exist_ok=True)
    shapes = [(t, evolving.at(t)) for t in times]
    present = [s for _, s in shapes if s is not None]
    if not present:
        return []
    everything = np.concatenate([s.vertices for s in present])
    low, high = everything.min(axis=0), everything.max(axis=0)
    paths = []
    for i, (t, shape) in enumerate(shapes):
        figure = plt.figure(figsize=(6, 4.5), dpi=100)
        axes = figure.add_subplot(projection="3d")
        if shape is not None and shape.n_cells:
            cells = shape.cells[:: max(1, shape.n_cells // max_triangles)]
            axes.plot_trisurf(
                shape.vertices[:, 0],
                shape.vertices[:, 1],
                shape.vertices[:, 2],
                triangles=cells,
                cmap="viridis",
                vmin=low[2],
                vmax=high[2],
                linewidth=0,
            )
        axes.set_xlim(low[0], high[0])
        axes.set_ylim(low[1], high[1])
        axes.set_zlim(low[2], high[2] if high[2] > low[2] else low[2] + 1)
        axes.set_title(f"{evolving.name or 'surface'} at t = {t:g}" + ("" if shape is not None else " (absent)"))
        path = target / f"{stem}_{i:03d}.png"
        figure.savefig(path)
        plt.close(figure)
        paths.append(path)
    return paths
