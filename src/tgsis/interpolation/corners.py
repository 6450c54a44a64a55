"""Corner detection: a proposal of control vertices on a disk-like surface with clear corners.

Control vertices are usually the corners of a surface's border (the four
corners of a horizon cut by four faults). :func:`propose_corners` finds the
border vertices where the border turns sharply, so that a modeller can accept
or edit the proposal instead of picking every vertex by hand.

The turn at a border vertex is measured between the chords to the border
points a little before and a little after it along the loop (a fixed
fraction of the loop's length), not between its two edges: a finely
triangulated straight border with small wiggles then shows no corner, and a
corner cut by a short chamfer still shows as one. Corners are the vertices
where that turn is at least ``min_angle`` and largest within the window.
"""

from __future__ import annotations

import numbers

import numpy as np
import numpy.typing as npt

from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.topology import MeshTopology
from tgsis.mesh import Surface

__all__ = ["border_turns", "propose_corners"]

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


def _points_at(points: FloatArray, arc: FloatArray, total: float, at: FloatArray) -> FloatArray:
    """Points of the closed polyline (``arc``: cumulative length at each vertex) at arc lengths ``at`` (wrapped)."""
    closed = np.concatenate([points, points[:1]])
    s = np.concatenate([arc, [total]])
    at = np.mod(at, total)
    return np.stack([np.interp(at, s, closed[:, j]) for j in range(3)], axis=1)


def border_turns(surface: Surface, loop: IntArray, window: float = 0.02) -> FloatArray:
    """Turning angle (degrees, 0 = straight on) of the border at each vertex of ``loop``.

    Parameters
    ----------
    surface : Surface
    loop : (k,) int64
        A border loop (ordered vertex indices).
    window : float
        Chord length either side, as a fraction of the loop's length.

    Returns
    -------
    (k,) float64
    """
    points = surface.vertices[loop]
    steps = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    total = float(steps.sum())
    arc = np.concatenate([[0.0], np.cumsum(steps)[:-1]])
    reach = window * total
    before = _points_at(points, arc, total, arc - reach)
    after = _points_at(points, arc, total, arc + reach)
    a, b = points - before, after - points
    cos = np.einsum("ij,ij->i", a, b) / np.maximum(np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1), 1e-300)
    turns: FloatArray = np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))
    return turns


def propose_corners(
    surface: Surface, *, min_angle: float = 35.0, window: float = 0.02, count: int | None = None
) -> IntArray:
    """Border vertices where the border of a disk-like surface turns sharply, in border order.

    Parameters
    ----------
    surface : Surface
        A surface with one border loop.
    min_angle : float
        Smallest turn (degrees) that makes a corner.
    window : float
        Chord length either side of a vertex, as a fraction of the border's length.
    count : int, optional
        Exactly this many corners: the ``count`` sharpest ones (refused when
        fewer turn by ``min_angle`` or more).

    Returns
    -------
    (c,) int64
        Vertex indices along the border loop (in the triangles' direction),
        starting at the sharpest corner.

    Raises
    ------
    InterpolationSetupError
        The surface has no border or several border loops, or fewer than
        ``count`` corners stand out; ``count`` < 1, ``min_angle`` outside
        [0, 180] or NaN, ``window`` outside (0, 0.5).
    """
    if isinstance(count, bool) or (count is not None and not (isinstance(count, numbers.Integral) and count >= 1)):
        raise InterpolationSetupError(f"count must be an integer >= 1 (or None: every corner), got {count!r}")
    if isinstance(min_angle, bool) or not (isinstance(min_angle, numbers.Real) and 0 <= min_angle <= 180):
        raise InterpolationSetupError(f"min_angle must be a number of degrees from 0 to 180, got {min_angle!r}")
    if isinstance(window, bool) or not (isinstance(window, numbers.Real) and 0 < window < 0.5):
        raise InterpolationSetupError(
            f"window must be a fraction of the border's length between 0 and 0.5, got {window!r}"
        )
    loops = MeshTopology.of(surface).border_loops
    if len(loops) != 1:
        raise InterpolationSetupError(
            f"corner detection needs a surface with one border loop, this one has {len(loops)}",
            hint="cut it into disks, or give control vertices by hand",
        )
    loop = loops[0]
    turns = border_turns(surface, loop, window)
    # a corner is the sharpest vertex within its window: compare with the neighbours within reach
    points = surface.vertices[loop]
    steps = np.linalg.norm(np.roll(points, -1, axis=0) - points, axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)[:-1]])
    total = float(steps.sum())
    reach = window * total
    order = np.argsort(-turns, kind="stable")
    taken: list[int] = []
    for i in order.tolist():
        if turns[i] < min_angle:
            break
        if any(min(abs(arc[i] - arc[j]), total - abs(arc[i] - arc[j])) <= reach for j in taken):
            continue
        taken.append(i)
        if count is not None and len(taken) == count:
            break
    if count is not None and len(taken) < count:
        raise InterpolationSetupError(
            f"only {len(taken)} corners stand out on the border, {count} were asked for",
            hint="lower min_angle, or give the control vertices by hand",
        )
    if not taken:
        return np.empty(0, dtype=np.int64)
    ranked = np.sort(np.asarray(taken, dtype=np.int64))
    start = int(np.argmax(turns[ranked]))
    return loop[np.roll(ranked, -start)].astype(np.int64)
