"""Model 5: extrusion of an n-G-map along a new axis, and slices at a value of one axis."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGMapError, InvalidInputError
from tgsis.gmaps._arrays import IntArray
from tgsis.gmaps._core import GMap, Properties


def extrude(g: GMap, values: npt.ArrayLike) -> GMap:
    """The (n + 1)-G-map of ``g`` x [v0, v1] u ... u [v(k-1), vk] (dimension-independent extrusion).

    Every n-cell sigma of ``g`` becomes one (n + 1)-cell sigma x [vj, vj+1]
    per interval; consecutive intervals are sewn by alpha_(n+1) across
    sigma x {vj}, the first and last layers stay free. The flags of
    sigma x I are (dart x of sigma, end e of the interval, step p = 1..n+1
    at which the flag leaves the layer): c_q = sigma_q x {v_e} for q < p and
    sigma_(q-1) x I for q >= p.

    Parameters
    ----------
    g : GMap
        Any n-G-map, points in R^m.
    values : (k + 1,) array_like of float
        Strictly increasing values of the new axis, k >= 1.

    Returns
    -------
    GMap
        Dimension n + 1, ``2 (n + 1) k d`` darts, points in R^(m+1): layer l
        holds ``g``'s points (in order, rows ``l K .. (l + 1) K - 1``) with
        ``values[l]`` appended. (n+1)-cell ``j n_cells(n) + c`` is cell c of
        ``g`` over interval j. Properties of ``g``'s n-cells become
        properties of the (n + 1)-cells (repeated per interval); properties
        of lower levels are dropped (the product's i-cells mix sigma x {v}
        and tau x I, which have no common source).

    Raises
    ------
    InvalidInputError
        ``values`` not finite, not 1-D, fewer than two, or not strictly increasing.
    """
    raw = np.asarray(values)
    if raw.dtype.kind not in "iuf" or raw.ndim != 1 or len(raw) < 2:
        raise InvalidInputError(
            f"values must be a 1-D array of at least two numbers, got {raw.dtype} of shape {raw.shape}"
        )
    vals = raw.astype(np.float64)
    if not np.isfinite(vals).all():
        raise InvalidInputError(f"values must be finite, got {vals[~np.isfinite(vals)][0]}")
    down = np.flatnonzero(np.diff(vals) <= 0)
    if len(down):
        at = int(down[0])
        raise InvalidInputError(
            f"values must be strictly increasing: values[{at}] = {vals[at]} and values[{at + 1}] = {vals[at + 1]}"
        )
    n, d, kp = g.dimension, g.n_darts, g.n_points
    k = len(vals) - 1
    steps = n + 1
    big_n = n + 1

    def idx(j: IntArray, p: IntArray | np.int64, e: IntArray | np.int64, x: IntArray) -> IntArray:
        return ((j * steps + (p - 1)) * 2 + e) * d + x

    shape = (k, steps, 2, d)
    j = np.arange(k, dtype=np.int64).reshape(k, 1, 1, 1)
    p = np.arange(1, steps + 1, dtype=np.int64).reshape(1, steps, 1, 1)
    e = np.arange(2, dtype=np.int64).reshape(1, 1, 2, 1)
    x = np.arange(d, dtype=np.int64).reshape(1, 1, 1, d)
    self_ = np.broadcast_to(idx(j, p, e, x), shape)
    rows = []
    for i in range(big_n + 1):
        out = np.array(self_)
        for q in range(1, steps + 1):  # the block of step p = q
            block = out[:, q - 1]
            if i < q - 1:
                block[...] = idx(j[:, 0], np.int64(q), e[:, 0], g.alpha[i].reshape(1, 1, d))
            elif i == q - 1:
                if q == 1:
                    block[...] = idx(j[:, 0], np.int64(1), 1 - e[:, 0], x[:, 0])
                else:
                    block[...] = idx(j[:, 0], np.int64(q - 1), e[:, 0], x[:, 0])
            elif i == q and q <= n:
                block[...] = idx(j[:, 0], np.int64(q + 1), e[:, 0], x[:, 0])
            elif i == q:  # q == n + 1: across the layer into the next (e = 1) or previous (e = 0) interval
                if k > 1:
                    block[:-1, 1] = idx(j[1:, 0, 0], np.int64(q), np.int64(0), x[0, 0])
                    block[1:, 0] = idx(j[:-1, 0, 0], np.int64(q), np.int64(1), x[0, 0])
            else:  # i > q
                block[...] = idx(j[:, 0], np.int64(q), e[:, 0], g.alpha[i - 1].reshape(1, 1, d))
        rows.append(out.reshape(-1))
    vertex = np.broadcast_to((j + e) * kp + g.vertex.reshape(1, 1, 1, d), shape).reshape(-1)
    points = np.concatenate([np.tile(g.points, (k + 1, 1)), np.repeat(vals, kp)[:, None]], axis=1)
    props: Properties = {}
    if n in g.cell_properties:
        props[big_n] = {name: np.concatenate([v] * k) for name, v in g.cell_properties[n].items()}
    return GMap(np.stack(rows), vertex, points, cell_properties=props)


def _take_properties(g: GMap, chosen: IntArray, result: GMap) -> Properties:
    """Properties of g's top cells for the result's top cells, whose darts come from ``chosen``."""
    top = g.dimension
    if top not in g.cell_properties or result.n_darts == 0:
        return {}
    source = g.cells(top)[chosen[result.cell_darts(top - 1)]]
    return {top - 1: {name: v[source] for name, v in g.cell_properties[top].items()}}


def _empty(g: GMap, axis: int) -> GMap:
    return GMap(
        np.empty((g.dimension, 0), dtype=np.int64),
        np.empty(0, dtype=np.int64),
        np.empty((0, g.embedding_dimension - 1)),
    )


def _walk(start: IntArray, first: IntArray, second: IntArray, stop: npt.NDArray[np.bool_], what: str) -> IntArray:
    """For each start: apply ``first``, then ``second`` and ``first`` again until a dart in ``stop``.

    A dart free in ``second`` ends the walk at its start (a border).
    """
    result = start.copy()
    cur = first[start]
    todo = np.arange(len(start))
    for _ in range(len(first) + 1):
        done = stop[cur[todo]]
        result[todo[done]] = cur[todo[done]]
        todo = todo[~done]
        if len(todo) == 0:
            return result
        nxt = second[cur[todo]]
        free = nxt == cur[todo]
        result[todo[free]] = start[todo[free]]
        todo, nxt = todo[~free], nxt[~free]
        cur[todo] = first[nxt]
    raise InvalidGMapError(
        f"the {what} of the slice cannot be found: the map is not a valid G-map", hint="run check() first"
    )


def slice(g: GMap, axis: int, value: float) -> GMap:  # noqa: A001 - the operation's name in the spec
    """The (n - 1)-G-map of ``g`` at ``points[:, axis] == value`` (points lose that coordinate).

    Two cases are supported, which cover every slice of an extrusion:

    * the value is that of some vertices, and no edge crosses it (a layer of
      an extrusion): the result is made of the (n-1)-faces lying in the
      plane, each taken from the n-cell above it (or from its only n-cell on
      the border). A slice of :func:`extrude` at one of its values gives the
      extruded map back dart for dart, point for point (points no dart used
      are not kept);
    * no vertex has the value: the section of the n-cells that cross it; an
      (i + 1)-cell crossing the plane gives an i-cell, each crossing edge a
      point, interpolated linearly (between two layers of an extrusion: the
      layer in between, with the same darts and cells).

    A plane through some vertices while edges cross it (a general cut) is
    refused. Properties of ``g``'s n-cells go to the (n - 1)-cells they give
    (a face in the plane takes those of the cell above it); other
    properties are dropped.

    Parameters
    ----------
    g : GMap
        An n-G-map, n >= 1, points in R^m.
    axis : int
        Coordinate index, 0 <= axis < m.
    value : float
        Where to cut.

    Returns
    -------
    GMap
        Dimension n - 1, points in R^(m-1); no dart when the object does not
        reach ``value``.

    Raises
    ------
    InvalidInputError
        Bad axis or value, a 0-G-map, or a cut this function does not support
        (the message says why).
    InvalidGMapError
        ``g`` breaks the G-map conditions so that the slice cannot be built.
    """
    n = g.dimension
    if n == 0:
        raise InvalidInputError("a 0-G-map (points) cannot be sliced")
    if isinstance(axis, bool) or not isinstance(axis, (int, np.integer)) or not 0 <= axis < g.embedding_dimension:
        raise InvalidInputError(f"axis must be an integer in 0..{g.embedding_dimension - 1}, got {axis!r}")
    try:
        at = float(value)
    except (TypeError, ValueError):
        raise InvalidInputError(f"value must be a number, got {value!r}") from None
    if not np.isfinite(at):
        raise InvalidInputError(f"value must be finite, got {at}")
    a = g.alpha
    coord = g.points[:, axis]
    xd = coord[g.vertex]
    on, below, above = xd == at, xd < at, xd > at
    crossing = below & above[a[0]]
    if on.any():
        if crossing.any():
            x = int(np.flatnonzero(crossing)[0])
            raise InvalidInputError(
                f"the plane {axis} = {at} passes through vertices and crosses edges (dart {x}, from point "
                f"{int(g.vertex[x])} to point {int(g.vertex[a[0, x]])}): only slices through whole layers of "
                "faces, or through no vertex, are supported"
            )
        return _slice_layer(g, axis, on, above)
    if not crossing.any():
        return _empty(g, axis)
    return _slice_between(g, axis, at, crossing)


def _slice_layer(g: GMap, axis: int, on: npt.NDArray[np.bool_], above: npt.NDArray[np.bool_]) -> GMap:
    n, a, d = g.dimension, g.alpha, g.n_darts
    darts = np.arange(d, dtype=np.int64)
    faces, n_faces = g.orbits(range(n - 1))  # (n-1)-faces as seen from one n-cell
    flat = np.bincount(faces, weights=on, minlength=n_faces) == np.bincount(faces, minlength=n_faces)
    in_plane = flat[faces]
    cells, n_cells_ = g.orbits(range(n))
    cell_above = np.bincount(cells, weights=above, minlength=n_cells_) > 0
    other = a[n]
    free = other == darts
    up, up_other = cell_above[cells], cell_above[cells[other]]
    ambiguous = in_plane & ~free & (up == up_other)
    if ambiguous.any():
        x = int(np.flatnonzero(ambiguous)[0])
        raise InvalidInputError(
            f"the face of dart {x} lies in the plane {axis} = {g.points[g.vertex[x], axis]} "
            "but does not separate a cell above from a cell below: not supported"
        )
    chosen_mask = in_plane & (free | (up & ~up_other))
    chosen = np.flatnonzero(chosen_mask).astype(np.int64)
    lone = np.setdiff1d(g.vertex[on], g.vertex[chosen])
    if len(lone):
        raise InvalidInputError(
            f"point {int(lone[0])} lies in the plane {axis} = "
            f"{g.points[lone[0], axis]} but on no face in it: not supported "
            f"({len(lone)} such points)"
        )
    if len(chosen) == 0:
        return _empty(g, axis)
    index = np.full(d, -1, dtype=np.int64)
    index[chosen] = np.arange(len(chosen))
    rows = [index[a[i, chosen]] for i in range(n - 1)]
    if n >= 2:
        rows.append(index[_walk(chosen, a[n - 1], a[n], chosen_mask, "top involution")])
    else:
        rows.append(np.arange(len(chosen), dtype=np.int64))
    return _assemble(g, axis, chosen, rows, g.vertex[chosen], None)


def _slice_between(g: GMap, axis: int, at: float, crossing: npt.NDArray[np.bool_]) -> GMap:
    n, a = g.dimension, g.alpha
    chosen = np.flatnonzero(crossing).astype(np.int64)
    index = np.full(g.n_darts, -1, dtype=np.int64)
    index[chosen] = np.arange(len(chosen))
    if n >= 2:
        rows = [index[_walk(chosen, a[1], a[0], crossing, "alpha0")]]
        # _walk's border rule (free alpha0) never applies: alpha0 has no fixed points in a valid map
        rows += [index[a[i + 1, chosen]] for i in range(1, n)]
    else:
        rows = [np.arange(len(chosen), dtype=np.int64)]
    low, high = g.vertex[chosen], g.vertex[a[0, chosen]]
    return _assemble(g, axis, chosen, rows, low, (high, at))


def _assemble(
    g: GMap, axis: int, chosen: IntArray, rows: list[IntArray], low: IntArray, between: tuple[IntArray, float] | None
) -> GMap:
    alpha = np.stack(rows)
    if (alpha < 0).any():
        raise InvalidGMapError(
            "an involution leads a dart of the slice out of it: the map is not a valid G-map", hint="run check() first"
        )
    kp = g.n_points
    key = low if between is None else low * kp + between[0]
    unique, vertex = np.unique(key, return_inverse=True)
    if between is None:
        points = g.points[unique]
    else:
        pa, pb = g.points[unique // kp], g.points[unique % kp]
        s = (between[1] - pa[:, axis]) / (pb[:, axis] - pa[:, axis])
        # where both ends agree keep the coordinate itself (bit for bit: -0.0 + 0.0 would be 0.0)
        points = np.where(pa == pb, pa, pa + s[:, None] * (pb - pa))
    result = GMap(alpha, vertex.astype(np.int64).reshape(-1), np.delete(points, axis, axis=1))
    props = _take_properties(g, chosen, result)
    if props:
        result = GMap(result.alpha, result.vertex, result.points, cell_properties=props)
    return result
