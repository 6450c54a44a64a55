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

from tgsis.interpolation.cutting import cut_along_paths
from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.parameterize import compatible_patch
from tgsis.interpolation.partition import Patch, partition_pair
from tgsis.interpolation.projection import ControllingSurface
from tgsis.interpolation.setup import InterpolationSetup
from tgsis.interpolation.trajectories import evolving_surface, vertex_trajectories
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface

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
    """

    source: Surface
    target: Surface
    trajectories: FloatArray
    evolving: EvolvingSurface
    error: float
    timings: dict[str, float] = field(default_factory=dict)


def _patch_arrays(mesh: Surface, patch: Patch) -> tuple[FloatArray, IntArray, IntArray, IntArray]:
    """(local vertices, local triangles, global ids of the local vertices, local controls in border order)."""
    ids = np.unique(mesh.cells[patch.triangles])
    local = np.full(mesh.n_vertices, -1, dtype=np.int64)
    local[ids] = np.arange(len(ids))
    return (mesh.vertices[ids], local[mesh.cells[patch.triangles]], ids.astype(np.int64),
            local[np.asarray(patch.control_vertices, dtype=np.int64)])


def _controlling_surfaces(setup: InterpolationSetup,
                          loader: Callable[[str], Surface] | None) -> dict[str, ControllingSurface]:
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
        mesh = loader(path)
        surfaces[name] = ControllingSurface(mesh.vertices, mesh.cells, name=name)
    return surfaces


def interpolate(source: Surface, target: Surface, setup: InterpolationSetup, t0: float, t1: float, *,
                name: str | None = None,
                surfaces: Mapping[str, Surface] | None = None) -> Interpolation:
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
    if not (np.isfinite(t0) and np.isfinite(t1) and t0 != t1):
        raise InterpolationSetupError(f"the source and target times must be two different finite times, "
                                      f"got t0={t0}, t1={t1}")
    timings: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(stage: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        timings[stage] = now - clock
        clock = now

    # 1. cutting: copies are appended, so the set-up's vertex indices keep their meaning
    if setup.cuts:
        cut = cut_along_paths(source, [list(c.path) for c in setup.cuts], names=[c.name for c in setup.cuts])
        source = cut.surface
    lap("cut")
    # 3. partition and pairing
    pairing = partition_pair(source, target, list(setup.source_controls), list(setup.target_controls),
                             [list(p) for p in setup.source_fences], [list(p) for p in setup.target_fences],
                             source_fence_names=list(setup.fence_names) if setup.fence_names else None)
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
        result = compatible_patch(s_xyz, s_tri, s_ctl, t_xyz, t_tri, t_ctl, tolerance)
        error = max(error, result.error)
        added = len(result.source_vertices) - len(s_ids)
        first_new = n + sum(len(v) for v in extra_vertices)
        to_global = np.concatenate([s_ids, first_new + np.arange(added, dtype=np.int64)])
        extra_vertices.append(result.source_vertices[len(s_ids):])
        known = ~np.isnan(positions[s_ids, 0])  # fence vertices placed by a patch before: the patches agree there
        positions[s_ids[~known]] = result.target_positions[: len(s_ids)][~known]
        positions = np.concatenate([positions, result.target_positions[len(s_ids):]])
        triangles.append(to_global[result.triangles])
    lap("compatible")
    all_vertices = np.concatenate([source.vertices, *extra_vertices])
    cells = np.concatenate(triangles)
    unused = np.isnan(positions[:, 0])
    if unused.any():  # vertices on no triangle (none in a valid partition)
        positions[unused] = all_vertices[unused]
    # 5. trajectories, with attachments
    named = _controlling_surfaces(setup, (lambda path: _named_surface(surfaces, path, setup)) if surfaces else None)
    attachments = {a.vertex: [named[s] for s in a.surfaces] for a in setup.attachments}
    samples = vertex_trajectories(all_vertices, positions, cells, setup.steps, attachments or None,
                                  controls=list(setup.source_controls))
    lap("trajectories")
    # samples run from the source (t0) to the target (t1); an evolving surface runs forward in time
    evolving = (evolving_surface(cells, samples, t0, t1, name=name) if t0 < t1
                else evolving_surface(cells, samples[::-1].copy(), t1, t0, name=name))
    lap("evolving")
    log.info("interpolated %d vertices, %d triangles, %d patches, m = %d: %s", len(all_vertices), len(cells),
             len(pairing.pairs), setup.steps, ", ".join(f"{k} {v:.2f} s" for k, v in timings.items()))
    return Interpolation(Surface(all_vertices, cells, name=source.name), Surface(positions, cells, name=target.name),
                         samples, evolving, error, timings)


def _named_surface(surfaces: Mapping[str, Surface] | None, path: str, setup: InterpolationSetup) -> Surface:
    """The controlling surface given by name for the set-up entry whose file is ``path``."""
    assert surfaces is not None
    for name, file in setup.controlling_surfaces.items():
        if file == path and name in surfaces:
            return surfaces[name]
    raise InterpolationSetupError(f"no controlling surface given for {path}",
                                  hint=f"pass surfaces={{name: Surface}} for {sorted(setup.controlling_surfaces)}")


def average_shape(first: Surface, second: Surface, setup: InterpolationSetup,
                  surfaces: Mapping[str, Surface] | None = None) -> Surface:
    """The "average" of two versions of a surface: their interpolation at the middle time (manual conflict solving).

    Returns
    -------
    Surface
        The first version's (cut, refined) topology at the middle shape.
    """
    result = interpolate(first, second, setup, 0.0, 1.0, surfaces=surfaces)
    middle = result.evolving.at(0.5)
    assert middle is not None
    return Surface(middle.vertices, middle.cells, name=first.name)
