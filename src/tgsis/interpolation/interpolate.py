"""The whole interpolation: cut, partition, compatible patches, stitching, trajectories, evolving surface.

:func:`interpolate` runs the spec's four procedures in order on a source
and a target surface with an :class:`~tgsis.interpolation.setup.InterpolationSetup`
and returns an :class:`Interpolation`, whose ``evolving`` is a model-3
:class:`~tgsis.temporal.EvolvingSurface` (store it with
:func:`tgsis.insert_feature` in an EVOLVING class). :func:`average_shape`
is the merge helper: the interpolated shape at the middle time.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from tgsis._zpositive import elevation
from tgsis.interpolation.cutting import cut_along_paths
from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.parameterize import compatible_patch
from tgsis.interpolation.partition import Patch, partition_pair
from tgsis.interpolation.projection import ControllingSurface
from tgsis.interpolation.setup import InterpolationSetup
from tgsis.interpolation.trajectories import evolving_surface, vertex_trajectories
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, TopologyPeriod

__all__ = ["Interpolation", "interpolate", "average_shape"]

log = logging.getLogger(__name__)

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


@dataclass
class Interpolation:
    """The result of :func:`interpolate`.

    Attributes
    ----------
    source : Surface
        The source as interpolated: cut along the cutting paths and refined
        (same shape as the given source).
    target : Surface
        The compatible target: the source's topology, every vertex on the target.
    trajectories : (m, n, 3) float64
        Position of every vertex at the m instants.
    evolving : EvolvingSurface
        One topology period from t0 to t1 (``evolving.at(t)`` is the mesh at t).
    error : float
        Largest error between a compatible target patch and its target patch.
    timings : dict of str to float
        Seconds spent per stage.
    dropped_properties : tuple of str
        Vertex properties of only one of the two meshes: not interpolated.
    """

    source: Surface
    target: Surface
    trajectories: FloatArray
    evolving: EvolvingSurface
    error: float
    timings: dict[str, float] = field(default_factory=dict)
    dropped_properties: tuple[str, ...] = ()


def _patch_arrays(mesh: Surface, patch: Patch) -> tuple[FloatArray, IntArray, IntArray, IntArray]:
    """(local vertices, local triangles, global ids of the local vertices, local controls in border order)."""
    ids = np.unique(mesh.cells[patch.triangles])
    local = np.full(mesh.n_vertices, -1, dtype=np.int64)
    local[ids] = np.arange(len(ids))
    return (
        mesh.vertices[ids],
        local[mesh.cells[patch.triangles]],
        ids.astype(np.int64),
        local[np.asarray(patch.control_vertices, dtype=np.int64)],
    )


def _controlling_surfaces(
    setup: InterpolationSetup, loader: Callable[[str], Surface] | None
) -> dict[str, ControllingSurface]:
    if not setup.controlling_surfaces:
        return {}
    if loader is None:
        from tgsis import formats

        def loader(path: str) -> Surface:
            mesh = formats.read_one(path)
            if not isinstance(mesh, Surface):
                raise InterpolationSetupError(f"controlling surface {path} is a {type(mesh).__name__}, not a surface")
            return mesh

    surfaces = {}
    for name, path in setup.controlling_surfaces.items():
        mesh = elevation(loader(path))  # z up, as the source and target are
        surfaces[name] = ControllingSurface(mesh.vertices, mesh.cells, name=name)
    return surfaces


def _values_at(
    mesh: Surface, values: Mapping[str, npt.NDArray[np.generic]], points: FloatArray, names: list[str]
) -> dict[str, FloatArray]:
    """Vertex property values of ``mesh`` at points on (or next to) it, barycentric in the nearest triangle.

    The candidates are the triangles whose centroids are nearest; of those,
    the one the point projects into (else the closest after clamping its
    barycentric coordinates onto the triangle) gives the weights. A corner
    without a value (NaN: no property row) is left out and the weights of
    the others renormalised, so a missing value does not spread to every
    point of the triangles around it; the value is NaN only where the
    corners with values have no weight (the point is at the missing one).
    """
    from scipy.spatial import cKDTree

    corners = mesh.vertices[mesh.cells]  # (m, 3, 3)
    k = min(8, len(mesh.cells))
    _, nearest = cKDTree(corners.mean(axis=1)).query(points, k=k)
    nearest = np.asarray(nearest).reshape(len(points), k)
    a, b, c = (corners[nearest, i] for i in range(3))  # (p, k, 3) each
    e0, e1, d = b - a, c - a, points[:, None, :] - a
    d00, d01, d11 = (e0 * e0).sum(-1), (e0 * e1).sum(-1), (e1 * e1).sum(-1)
    d20, d21 = (d * e0).sum(-1), (d * e1).sum(-1)
    det = np.where(np.abs(d00 * d11 - d01 * d01) > 0, d00 * d11 - d01 * d01, 1.0)
    v = (d11 * d20 - d01 * d21) / det
    w = (d00 * d21 - d01 * d20) / det
    weights = np.stack([1.0 - v - w, v, w], axis=-1)  # (p, k, 3)
    clamped = np.clip(weights, 0.0, None)
    clamped /= np.maximum(clamped.sum(-1, keepdims=True), 1e-300)
    foot = (clamped[..., :, None] * np.stack([a, b, c], axis=-2)).sum(-2)
    best = np.argmin(((points[:, None, :] - foot) ** 2).sum(-1), axis=1)  # (p,)
    rows = np.arange(len(points))
    chosen, triangle = clamped[rows, best], nearest[rows, best]
    ids = mesh.cells[triangle]
    return {name: _weighted(chosen, np.asarray(values[name], dtype=np.float64)[ids]) for name in names}


def _weighted(weights: FloatArray, corner_values: FloatArray) -> FloatArray:
    """(p,) sums of (p, 3) weights times corner values; NaN corners left out, the other weights renormalised."""
    missing = np.isnan(corner_values)
    plain = (weights * corner_values).sum(-1)
    if not missing.any():
        return np.asarray(plain, dtype=np.float64)
    known = np.where(missing, 0.0, weights)
    total = known.sum(-1)
    renormalised = (known * np.where(missing, 0.0, corner_values)).sum(-1) / np.where(total > 0.0, total, 1.0)
    out = np.where(missing.any(-1), np.where(total > 0.0, renormalised, np.nan), plain)
    return np.asarray(out, dtype=np.float64)


def _carried_properties(
    source: Surface, target: Surface, all_vertices: FloatArray, positions: FloatArray, steps: int
) -> tuple[dict[str, FloatArray], tuple[str, ...]]:
    """(m, n) values of the vertex properties both meshes have, linear along each trajectory; and the others' names.

    A vertex starts with the source's value (its own, or for a vertex the
    refinement added, the source's value where it lies) and ends with the
    target's value where its compatible position lies on the target.
    """
    names = sorted(set(source.vertex_properties) & set(target.vertex_properties))
    dropped = tuple(sorted(set(source.vertex_properties) ^ set(target.vertex_properties)))
    if not names:
        return {}, dropped
    n = source.n_vertices
    start = {name: np.asarray(source.vertex_properties[name], dtype=np.float64) for name in names}
    if len(all_vertices) > n:
        extra = _values_at(source, source.vertex_properties, all_vertices[n:], names)
        start = {name: np.concatenate([start[name], extra[name]]) for name in names}
    end = _values_at(target, target.vertex_properties, positions, names)
    s = np.linspace(0.0, 1.0, steps)[:, None]
    return {name: (1.0 - s) * start[name][None] + s * end[name][None] for name in names}, dropped


def interpolate(
    source: Surface,
    target: Surface,
    setup: InterpolationSetup,
    t0: float,
    t1: float,
    *,
    name: str | None = None,
    surfaces: Mapping[str, Surface] | None = None,
    alive: bool = False,
    progress: Callable[[int, int], None] | None = None,
    split: str = "auto",
) -> Interpolation:
    """The surface evolving from ``source`` at ``t0`` to ``target`` at ``t1`` under the set-up's constraints.

    Parameters
    ----------
    source, target : Surface
    setup : InterpolationSetup
        Control vertex pairs, fence and cutting paths, attachments, m, ε.
    t0, t1 : float
        Times of the source and the target, in either order: the source may
        be the later shape (the more complex one, as the source design
        allows); the evolving surface then runs from the target at t1 to
        the source at t0, on the source's triangulation.
    name : str, optional
        Name of the evolving surface.
    surfaces : mapping of str to Surface, optional
        The controlling surfaces by name (default: read from the set-up's files).
    alive : bool
        Whether the evolving surface exists after its last instant (keeping its last shape).
    progress : callable, optional
        ``progress(done, total)`` after each step: cutting, partition, each
        pair of compatible patches, trajectories, the evolving surface (the
        total is known once the partition is).
    split : {"auto", "centroid"}
        How the compatible meshes are refined (:func:`compatible_patch`):
        ``"centroid"`` is the design's rule (the source triangle holding the
        closest point of a far target vertex is split at its centroid);
        ``"auto"`` (default) bisects its longest edge when that edge is
        interior, which converges where centroid splits stall.

    Vertex properties that both meshes carry travel with the vertices: each
    goes linearly from the source's value to the target's value where its
    compatible position lies (barycentric in the closest target triangle);
    properties of one mesh only are left out (``dropped_properties``).

    Returns
    -------
    Interpolation

    Raises
    ------
    InterpolationSetupError
        A set-up mistake, naming the path or patch at fault.
    ParameterizationError, TrajectoryError, ProjectionError
        A numeric failure (refinement not converging, a vertex off its surface).
    """
    if split not in ("auto", "centroid"):
        raise InterpolationSetupError(f"split {split!r} is not one of 'auto', 'centroid'")
    if not (np.isfinite(t0) and np.isfinite(t1) and t0 != t1):
        raise InterpolationSetupError(
            f"the source and target times must be two different finite times, got t0={t0}, t1={t1}"
        )
    # z up, as stored: a ZPOSITIVE Depth mesh (a GOCAD file, a fetched feature) negated, so that meshes of two
    # conventions morph into each other and the evolving surface is stored as the shape it is (not mirrored)
    source, target = elevation(source), elevation(target)
    timings: dict[str, float] = {}
    clock = time.perf_counter()
    steps = [0, 5]  # done, total (cut, partition, one per pair of patches, trajectories, evolving)

    def step() -> None:
        steps[0] += 1
        if progress is not None:
            progress(steps[0], steps[1])

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        timings[stage] = now - clock
        clock = now
        if stage != "compatible":  # counted per pair of patches
            step()

    # 1. cutting: copies are appended, so the set-up's vertex indices keep their meaning
    if setup.cuts:
        cut = cut_along_paths(source, [list(c.path) for c in setup.cuts], names=[c.name for c in setup.cuts])
        source = cut.surface
    lap("cut")
    # 3. partition and pairing
    pairing = partition_pair(
        source,
        target,
        list(setup.source_controls),
        list(setup.target_controls),
        [list(p) for p in setup.source_fences],
        [list(p) for p in setup.target_fences],
        source_fence_names=list(setup.fence_names) if setup.fence_names else None,
    )
    steps[1] = 4 + len(pairing.pairs)
    lap("partition")
    # 4. compatible patches, stitched along the fences they share
    n = source.n_vertices
    extra_vertices: list[FloatArray] = []
    positions = np.full((n, 3), np.nan)
    triangles: list[IntArray] = []
    error = 0.0
    tolerance = setup.tolerance if np.isfinite(setup.tolerance) else float(np.finfo(np.float64).max)
    for pair in pairing.pairs:
        s_patch = pairing.source.patches[pair.source]
        t_patch = pairing.target.patches[pair.target]
        s_xyz, s_tri, s_ids, s_ctl = _patch_arrays(source, s_patch)
        t_xyz, t_tri, _, t_ctl = _patch_arrays(target, t_patch)
        result = compatible_patch(s_xyz, s_tri, s_ctl, t_xyz, t_tri, t_ctl, tolerance, split=split)
        error = max(error, result.error)
        added = len(result.source_vertices) - len(s_ids)
        first_new = n + sum(len(v) for v in extra_vertices)
        to_global = np.concatenate([s_ids, first_new + np.arange(added, dtype=np.int64)])
        extra_vertices.append(result.source_vertices[len(s_ids) :])
        known = ~np.isnan(positions[s_ids, 0])  # fence vertices placed by a patch before: the patches agree there
        positions[s_ids[~known]] = result.target_positions[: len(s_ids)][~known]
        positions = np.concatenate([positions, result.target_positions[len(s_ids) :]])
        triangles.append(to_global[result.triangles])
        step()
    lap("compatible")
    all_vertices = np.concatenate([source.vertices, *extra_vertices])
    cells = np.concatenate(triangles)
    unused = np.isnan(positions[:, 0])
    if unused.any():  # vertices on no triangle (none in a valid partition)
        positions[unused] = all_vertices[unused]
    # 5. trajectories, with attachments
    named = _controlling_surfaces(setup, (lambda path: _named_surface(surfaces, path, setup)) if surfaces else None)
    attachments = {a.vertex: [named[s] for s in a.surfaces] for a in setup.attachments}
    samples = vertex_trajectories(
        all_vertices, positions, cells, setup.steps, attachments or None, controls=list(setup.source_controls)
    )
    lap("trajectories")
    carried, dropped = _carried_properties(source, target, all_vertices, positions, setup.steps)
    # samples run from the source (t0) to the target (t1); an evolving surface runs forward in time
    forward = evolving_surface(cells, samples, min(t0, t1), max(t0, t1), name=name, alive=alive)
    order = slice(None) if t0 < t1 else slice(None, None, -1)
    period = forward.periods[0]
    evolving = EvolvingSurface(
        [
            TopologyPeriod(
                period.times,
                cells,
                samples[order].copy(),
                vertex_properties={k: v[order].copy() for k, v in carried.items()},
            )
        ],
        name=name,
        alive=alive,
    )
    lap("evolving")
    log.info(
        "interpolated %d vertices, %d triangles, %d patches, m = %d: %s",
        len(all_vertices),
        len(cells),
        len(pairing.pairs),
        setup.steps,
        ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()),
    )
    return Interpolation(
        Surface(all_vertices, cells, name=source.name),
        Surface(positions, cells, name=target.name),
        samples,
        evolving,
        error,
        timings,
        dropped,
    )


def _named_surface(surfaces: Mapping[str, Surface] | None, path: str, setup: InterpolationSetup) -> Surface:
    """The controlling surface given by name for the set-up entry whose file is ``path``."""
    assert surfaces is not None
    for name, file in setup.controlling_surfaces.items():
        if file == path and name in surfaces:
            return surfaces[name]
    raise InterpolationSetupError(
        f"no controlling surface given for {path}",
        hint=f"pass surfaces={{name: Surface}} for {sorted(setup.controlling_surfaces)}",
    )


def average_shape(
    first: Surface, second: Surface, setup: InterpolationSetup, surfaces: Mapping[str, Surface] | None = None
) -> Surface:
    """The "average" of two versions of a surface: their interpolation at the middle time (manual conflict solving).

    Returns
    -------
    Surface
        The first version's (cut, refined) topology at the middle shape,
        with the vertex properties both versions carry at their middle
        values (as :func:`interpolate` carries them).
    """
    result = interpolate(first, second, setup, 0.0, 1.0, surfaces=surfaces)
    middle = result.evolving.at(0.5)
    assert middle is not None
    return Surface(middle.vertices, middle.cells, vertex_properties=dict(middle.vertex_properties), name=first.name)
