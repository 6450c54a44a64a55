"""Morphological interpolation of triangulated surfaces (issue 8; spec ``shared/spec/interpolation.md``).

Pure numpy/scipy, no database:

* :mod:`.parameterize`: disk patches onto the unit regular k-polygon (chord
  length border, mean value interior), point location in parameter meshes,
  compatible meshes refined to a tolerance;
* :mod:`.trajectories`: vertex trajectories (linear, projected onto
  controlling surfaces, interior by interpolated mean value weights) and the
  model-3 :class:`~tgsis.temporal.EvolvingSurface` they make;
* :mod:`.projection`: closest points on triangle meshes, controlling
  surfaces and their intersection curves.

The functions are not named after their modules (``parameterize_patch``,
``vertex_trajectories``) so that ``tgsis.interpolation.parameterize`` and
``tgsis.interpolation.trajectories`` stay the modules.
"""

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
from tgsis.interpolation.projection import (
    ClosestPoints,
    ControllingSurface,
    IntersectionCurve,
    ProjectionError,
    closest_points,
    intersection_curve,
)
from tgsis.interpolation.trajectories import (
    Attachments,
    TrajectoryError,
    border_trajectories,
    evolving_surface,
    vertex_trajectories,
)

__all__ = [
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
