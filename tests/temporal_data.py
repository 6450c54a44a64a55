"""Synthetic temporal surfaces for the model 2 and model 3 tests: grids that move and re-triangulate."""

from __future__ import annotations

import numpy as np

from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, SurfaceSeries, TopologyPeriod


def grid(side: int) -> tuple[np.ndarray, np.ndarray]:
    """(side², 3) flat grid vertices on [0, 1]² and its (2 (side-1)², 3) triangles."""
    u, v = np.meshgrid(np.linspace(0, 1, side), np.linspace(0, 1, side))
    vertices = np.stack([u.ravel(), v.ravel(), np.zeros(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def _values(
    rng: np.random.Generator, low: float, high: float, shape: tuple[int, ...], levels: int | None
) -> np.ndarray:
    """Uniform values, or with ``levels`` whole numbers 0..levels-1 (so that equal values and plateaus occur)."""
    return rng.uniform(low, high, shape) if levels is None else rng.integers(0, levels, shape).astype(np.float64)


def refine(positions: np.ndarray, side: int) -> np.ndarray:
    """(side'², 3) positions of the grid refined once (side' = 2 side - 1) whose every triangle lies in one of ``positions``'s.

    The refined grid's triangles are the midpoint subdivision of the
    coarse grid's (its diagonals run the same way), so the refined shape is
    the coarse shape itself: a topology change without a jump.
    """
    coarse = positions.reshape(side, side, 3)
    fine = np.empty((2 * side - 1, 2 * side - 1, 3))
    fine[::2, ::2] = coarse
    fine[::2, 1::2] = (coarse[:, :-1] + coarse[:, 1:]) / 2
    fine[1::2, ::2] = (coarse[:-1] + coarse[1:]) / 2
    fine[1::2, 1::2] = (coarse[:-1, :-1] + coarse[1:, 1:]) / 2  # on the diagonal a-d of grid()'s triangles
    return fine.reshape(-1, 3)


def evolving(
    rng: np.random.Generator,
    starts: list[float],
    instants_per_period: int = 3,
    side: int = 5,
    alive: bool = False,
    with_properties: bool = False,
    levels: int | None = None,
) -> EvolvingSurface:
    """Periods starting at ``starts`` (the last one lasting 1.0), each a grid whose nodes move randomly.

    Each period after the first is the grid of the one before refined once
    (a topology change), starting in the shape the one before ends in (the
    continuity of topology changes: docs/time.md). With ``levels``, porosity
    and throw are whole numbers below it.
    """
    ends = [*starts[1:], starts[-1] + 1.0]
    periods: list[TopologyPeriod] = []
    for i, (t0, t1) in enumerate(zip(starts, ends)):
        n = (side - 1) * 2**i + 1
        vertices, triangles = grid(n)
        inner = np.sort(rng.uniform(t0, t1, instants_per_period - 2))
        times = np.concatenate([[t0], inner, [t1]])
        positions = vertices[None] + rng.normal(scale=0.1, size=(len(times), len(vertices), 3))
        if periods:
            positions[0] = refine(periods[-1].positions[-1], (side - 1) * 2 ** (i - 1) + 1)
        extra = {}
        if with_properties:
            extra = dict(
                vertex_properties={"porosity": _values(rng, 0, 0.4, (len(times), len(vertices)), levels)},
                properties={"throw": _values(rng, 0, 100, (len(times),), levels), "note_code": np.arange(len(times))},
            )
        periods.append(TopologyPeriod(times, triangles, positions, **extra))
    return EvolvingSurface(periods, alive=alive, name="evolving fault")


def series(
    rng: np.random.Generator,
    times: list[float],
    alive: bool = False,
    with_properties: bool = False,
    levels: int | None = None,
) -> SurfaceSeries:
    """A surface at each instant, each a grid of its own size with random heights.

    With ``levels``, porosity and throw are whole numbers below it.
    """
    surfaces = []
    for i, _ in enumerate(times):
        vertices, triangles = grid(3 + i)
        vertices[:, 2] = rng.normal(size=len(vertices))
        props = {"porosity": _values(rng, 0, 0.4, (len(vertices),), levels)} if with_properties else {}
        surfaces.append(Surface(vertices, triangles, vertex_properties=props))
    properties = {"throw": _values(rng, 0, 100, (len(times),), levels)} if with_properties else {}
    return SurfaceSeries(times, surfaces, properties=properties, alive=alive, name="stepped horizon")
