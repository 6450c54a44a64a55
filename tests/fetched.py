"""What a test expects of a fetched feature, checked and typed: a geometry, or one mesh (not a collection)."""

from __future__ import annotations

from tgsis.db.features import Feature
from tgsis.mesh import Geometry, Mesh


def geometry_of(feature: Feature) -> Geometry:
    """The feature's mesh or collection, which the test expects it to have."""
    assert feature.mesh is not None, f"feature {feature.id} has no geometry"
    return feature.mesh


def mesh_of(feature: Feature) -> Mesh:
    """The feature's one mesh (a PointSet, LineSet, Surface or TetraMesh), which the test expects it to have."""
    assert isinstance(feature.mesh, Mesh), f"feature {feature.id} has {feature.mesh!r}, not one mesh"
    return feature.mesh
