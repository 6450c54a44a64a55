"""Polygons into triangles and polylines into segments (tgsis._polygons), the cuts the PostGIS reader and the view share."""

from __future__ import annotations

from tgsis._polygons import fan_triangles, polyline_segments


def test_polygons_are_cut_into_fans() -> None:
    # a quad, a triangle, a segment (no triangle) and a pentagon
    triangles, polygon = fan_triangles([0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13], [0, 4, 7, 9, 14])
    assert triangles.tolist() == [[0, 1, 2], [0, 2, 3], [4, 5, 6], [9, 10, 11], [9, 11, 12], [9, 12, 13]]
    assert polygon.tolist() == [0, 0, 1, 3, 3, 3]


def test_polylines_are_cut_into_their_segments_in_order() -> None:
    # three points, a lone point (no segment), nothing, two points
    segments = polyline_segments([4, 9, 2, 7, 5, 6], [0, 3, 4, 4, 6])
    assert segments.tolist() == [[4, 9], [9, 2], [5, 6]]
    assert polyline_segments([], [0]).shape == (0, 2)
    assert polyline_segments([3], [0, 1]).shape == (0, 2)
