"""Corner detection proposes control vertices at the sharp turns of a border."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import Delaunay

import tgsis
from tgsis.interpolation import InterpolationSetupError
from tgsis.interpolation.corners import border_turns, propose_corners


def _rectangle(nx: int, ny: int, bump: float = 0.0) -> tgsis.Surface:
    u, v = np.meshgrid(np.linspace(0, 3, nx), np.linspace(0, 2, ny))
    z = bump * np.exp(-((u - 1.5) ** 2 + (v - 1) ** 2))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        np.stack([u.ravel(), v.ravel(), z.ravel()], 1), np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
    )


def test_the_four_corners_of_a_dome() -> None:
    dome = _rectangle(31, 21, bump=1.0)
    corners = propose_corners(dome)
    assert sorted(corners.tolist()) == [0, 30, 20 * 31, 21 * 31 - 1]
    # in border order: consecutive corners are adjacent corners of the rectangle, not opposite ones
    xy = dome.vertices[corners, :2]
    sides = np.linalg.norm(np.roll(xy, -1, axis=0) - xy, axis=1)
    assert np.allclose(sorted(sides), [2, 2, 3, 3])


def test_a_round_border_has_no_corner_and_a_count_is_refused() -> None:
    angles = np.linspace(0, 2 * np.pi, 120, endpoint=False)
    rng = np.random.default_rng(0)
    inner = rng.random((300, 2)) * 1.2 - 0.6
    inner = inner[np.linalg.norm(inner, axis=1) < 0.9]
    xy = np.concatenate([np.stack([np.cos(angles), np.sin(angles)], 1), inner])
    disk = tgsis.Surface(np.column_stack([xy, np.zeros(len(xy))]), Delaunay(xy).simplices)
    assert propose_corners(disk).size == 0
    assert border_turns(disk, np.arange(120)).max() < 10
    with pytest.raises(InterpolationSetupError, match="only 4 corners stand out on the border, 5 were asked for"):
        propose_corners(_rectangle(5, 5), count=5)
    assert len(propose_corners(_rectangle(5, 5), count=3)) == 3


def test_wiggles_on_a_straight_side_are_not_corners() -> None:
    plate = _rectangle(41, 41)
    vertices = plate.vertices.copy()
    side = np.flatnonzero(vertices[:, 1] == 0)[1:-1]
    vertices[side, 1] += np.where(np.arange(len(side)) % 2 == 0, 0.01, -0.01)  # a saw-tooth of 1 % amplitude
    corners = propose_corners(tgsis.Surface(vertices, plate.cells))
    assert len(corners) == 4


def test_surfaces_without_one_border_are_refused() -> None:
    two = _rectangle(4, 4)
    shifted = tgsis.Surface(
        np.concatenate([two.vertices, two.vertices + [10, 0, 0]]), np.concatenate([two.cells, two.cells + 16])
    )
    with pytest.raises(InterpolationSetupError, match="one border loop, this one has 2"):
        propose_corners(shifted)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"count": 0}, "count must be an integer >= 1"),
        ({"count": -3}, "count must be an integer >= 1"),
        ({"count": 2.5}, "count must be an integer >= 1"),
        ({"min_angle": float("nan")}, "min_angle must be a number of degrees from 0 to 180"),
        ({"min_angle": -5.0}, "min_angle must be a number of degrees from 0 to 180"),
        ({"window": 0.0}, "window must be a fraction"),
    ],
)
def test_bad_arguments_are_refused(kwargs: dict[str, float], message: str) -> None:
    # before: count <= 0 or a NaN angle quietly gave some corners
    with pytest.raises(InterpolationSetupError, match=message):
        propose_corners(_rectangle(5, 5), **kwargs)  # type: ignore[arg-type]
