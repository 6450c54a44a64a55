"""Morphological interpolation of triangulated surfaces: the shapes between a source and a target mesh.

Set-up helpers (no database): mesh topology (:mod:`.topology`), cutting along
paths (:mod:`.cutting`), control vertices and fence paths (:mod:`.constraints`),
partition into patches and their pairing (:mod:`.partition`). Set-up mistakes
raise :class:`InterpolationSetupError`, naming the path or patch at fault.
"""

from __future__ import annotations

from tgsis.interpolation.constraints import validate_control_vertices, validate_fence_paths
from tgsis.interpolation.cutting import CutEnds, CutResult, cut_along_paths
from tgsis.interpolation.errors import InterpolationSetupError
from tgsis.interpolation.partition import (
    Partition,
    PartitionPairing,
    Patch,
    PatchPair,
    pair_patches,
    partition_pair,
    partition_surface,
)
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
]
