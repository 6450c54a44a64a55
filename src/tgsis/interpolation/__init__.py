"""Morphological interpolation of triangulated surfaces: the shapes between a source and a target mesh.

Spec ``../shared/spec/interpolation.md``. Pure numpy/scipy (networkx where a
graph algorithm is needed), no database:

* set-up: mesh topology (:mod:`.topology`), cutting along paths
  (:mod:`.cutting`), control vertices and fence paths (:mod:`.constraints`),
  partition into patches and their pairing (:mod:`.partition`), the set-up
  file (:mod:`.setup`), proposed corners (:mod:`.corners`);
* :mod:`.parameterize`: disk patches onto the unit regular k-polygon (chord
  length border, mean value interior), point location in parameter meshes,
  compatible meshes refined to a tolerance;
* :mod:`.trajectories`: vertex trajectories (linear, projected onto
  controlling surfaces, interior solved from its differential coordinates
  interpolated in time, one factorisation for all steps) and the
  model-3 :class:`~tgsis.temporal.EvolvingSurface` they make;
* :mod:`.deposition`: a unit deposited during an interval, growing from
  the surface beneath it (:func:`deposit`, :func:`drape`), and younger tops
  kept above older ones with their contact reported (:func:`keep_above`);
* :mod:`.projection`: closest points on triangle meshes, controlling
  surfaces and their intersection curves.

Set-up mistakes raise :class:`InterpolationSetupError`, naming the path or
patch at fault. The functions are not named after their modules
(``parameterize_patch``, ``vertex_trajectories``) so that
``tgsis.interpolation.parameterize`` and ``.trajectories`` stay the modules.
"""

from __future__ import annotations

from tgsis.interpolation.constraints import validate_control_vertices, validate_fence_paths
from tgsis.interpolation.corners import border_turns, propose_corners
from tgsis.interpolation.cutting import CutEnds, CutResult, cut_along_paths
from tgsis.interpolation.deposition import (
    Contact,
    Deposition,
    Stacking,
    deposit,
    drape,
    heights_below,
    keep_above,
)
from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.interpolate import Interpolation, average_shape, interpolate
from tgsis.interpolation.parameterize import (
    CompatiblePatch,
    Parameterization,
    ParameterizationError,
    PointLocator,
    compatible_patch,
    locate_points,
    mean_value_embedding,
    mean_value_weights,
    mesh_error,
    parameterize_patch,
    polygon_corners,
)
from tgsis.interpolation.partition import (
    Partition,
    PartitionPairing,
    Patch,
    PatchPair,
    pair_patches,
    partition_pair,
    partition_surface,
)
from tgsis.interpolation.projection import (
    ClosestPoints,
    ControllingSurface,
    IntersectionCurve,
    ProjectionError,
    closest_points,
    intersection_curve,
)
from tgsis.interpolation.setup import Attachment, CutPath, InterpolationSetup
from tgsis.interpolation.topology import (
    DiskCheck,
    MeshTopology,
    OneRings,
    border_edges,
    border_loops,
    border_vertices,
    check_disk,
    interior_vertices,
    mesh_edges,
    one_ring,
    one_rings,
    shortest_edge_path,
)
from tgsis.interpolation.trajectories import (
    Attachments,
    TrajectoryError,
    border_trajectories,
    evolving_surface,
    vertex_trajectories,
)

__all__ = [
    # errors
    "InterpolationSetupError",
    # topology
    "MeshTopology",
    "OneRings",
    "DiskCheck",
    "mesh_edges",
    "border_edges",
    "border_loops",
    "border_vertices",
    "interior_vertices",
    "one_rings",
    "one_ring",
    "shortest_edge_path",
    "check_disk",
    # cutting
    "CutEnds",
    "CutResult",
    "cut_along_paths",
    # constraints and partition
    "validate_control_vertices",
    "validate_fence_paths",
    "Patch",
    "Partition",
    "PatchPair",
    "PartitionPairing",
    "partition_surface",
    "pair_patches",
    "partition_pair",
    # the whole interpolation
    "interpolate",
    "Interpolation",
    "average_shape",
    # deposition: a unit growing from the surface beneath, younger tops above older ones
    "deposit",
    "Deposition",
    "drape",
    "heights_below",
    "keep_above",
    "Stacking",
    "Contact",
    # set-up file and corner proposals
    "InterpolationSetup",
    "CutPath",
    "Attachment",
    "propose_corners",
    "border_turns",
    # parameterisation, compatible meshes, projection, trajectories
    "Attachments",
    "ClosestPoints",
    "CompatiblePatch",
    "ControllingSurface",
    "IntersectionCurve",
    "Parameterization",
    "ParameterizationError",
    "PointLocator",
    "ProjectionError",
    "TrajectoryError",
    "border_trajectories",
    "closest_points",
    "compatible_patch",
    "evolving_surface",
    "intersection_curve",
    "locate_points",
    "mean_value_embedding",
    "mean_value_weights",
    "mesh_error",
    "parameterize_patch",
    "polygon_corners",
    "vertex_trajectories",
]
