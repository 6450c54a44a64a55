"""Generalized maps (n-G-maps) on numpy arrays: models 4 and 5 without the database.

An n-G-map is a set of darts with involutions alpha_0 .. alpha_n
(``../shared/spec/data-models.md``, model 4):

 (i)   alpha_i(alpha_i(d)) = d;
 (ii)  alpha_i(d) != d for i < n (only alpha_n may leave a dart free: the border);
 (iii) alpha_i o alpha_j is an involution for i + 2 <= j.

:class:`GMap` holds them as one ``(n + 1, d)`` int64 array ``alpha`` (a free
dart has ``alpha[i, x] == x``) and the linear embedding as a point index per
dart, ``vertex`` (d,), into ``points`` (k, m), m >= n. A point per dart,
rather than per 0-cell, is what the builders know without computing any
orbit, what the SQL relation ``dart(..., nodeid)`` stores, and it keeps a
mesh's vertex numbering through a round trip; that darts of one 0-cell
share their point is then a condition that :meth:`GMap.check` verifies.

* Orbits of any subset of the involutions (:meth:`GMap.orbits`), i-cells
  (:meth:`GMap.cells`: orbits of all involutions but alpha_i, numbered in the
  order of their lowest dart), counts, incidence and adjacency matrices, the
  border (:meth:`GMap.border`, an (n-1)-G-map), components, the Euler
  characteristic and orientation (:meth:`GMap.orientation`) — vectorised (min-label propagation finished by
  :func:`scipy.sparse.csgraph.connected_components`), no loop over darts.
* Builders: :func:`from_simplices` (points, segments, triangles with 6 darts
  each, tetrahedra with 24, any n), :func:`from_polygons` (faces of any
  sizes), :func:`from_mesh`; back to meshes with :meth:`GMap.simplices`,
  :meth:`GMap.polygons`, :meth:`GMap.polyhedra` and :meth:`GMap.to_mesh`.
* :meth:`GMap.check`: conditions (i)-(iii), shared points of 0-cells and,
  given a period per dart, the closure of every topology period (model 4),
  with the offending darts (:class:`GMapReport`).
* Model 5: :func:`extrude` (an n-G-map times a list of intervals of a new
  axis) and :func:`slice` (the (n-1)-G-map at a value of one axis).
* Properties of i-cells: ``GMap.cell_properties[level][name]``, one value per
  cell of that level.
* Model 4 in time: :class:`EvolvingGMap`, topology periods (:class:`GMapPeriod`)
  of fixed darts whose points and cell values move linearly between geometry
  instants; :meth:`EvolvingGMap.at` gives the G-map at t.

No database here, and nothing of :mod:`tgsis.db` is imported.

Examples
--------
>>> import numpy as np
>>> from tgsis import gmaps
>>> square = gmaps.GMap.from_polygons([[0, 0], [1, 0], [1, 1], [0, 1]], [[0, 1, 2, 3]])
>>> cube = gmaps.extrude(square, [0.0, 1.0])
>>> [cube.n_cells(i) for i in range(4)], cube.euler_characteristic()
([8, 12, 6, 1], 1)
>>> gmaps.slice(cube, 2, 0.0).same_as(square)
True
"""

from tgsis.gmaps._core import GMap, GMapReport, from_mesh, from_polygons, from_simplices, orbit_labels
from tgsis.gmaps._extrude import extrude, slice
from tgsis.gmaps._time import EvolvingGMap, GMapPeriod, sudden_gmap_change

__all__ = [
    "GMap",
    "GMapReport",
    "GMapPeriod",
    "EvolvingGMap",
    "sudden_gmap_change",
    "from_simplices",
    "from_polygons",
    "from_mesh",
    "orbit_labels",
    "extrude",
    "slice",
]
