"""Interpolation keeps the shape between the two known instants (issue 37, part 1; no database).

With an attaching constraint the interior trajectories are solved. The
source design's rule (each interior vertex a convex combination of its
neighbours with time-interpolated mean value weights) flattens any curved
surface between the known instants: a dome interpolated to itself was 0 m
high at t = 0.5. tgsis interpolates the vertices' differential coordinates
(their offsets from the mean-value combination of their neighbours) linearly
in time instead, the attached border as constraints. These tests state what
must hold: both known shapes come out of the solve, an identity or a rigid
translation is exact at every instant with any attachment, smooth relief is
kept within a stated bound, attached vertices stay on their controlling
surfaces, and one factorisation serves every step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

import tgsis
from tgsis.interpolation import Attachment, InterpolationSetup, interpolate, mean_value_weights, trajectories
from tgsis.interpolation._arrays import interior_mask
from tgsis.interpolation.projection import ControllingSurface
from tgsis.interpolation.trajectories import vertex_trajectories


def dome_grid(side: int = 21, width: float = 1000.0, height: float = 300.0) -> tgsis.Surface:
    """A 300 m dome over a width x width square as a side x side grid, 0 m high along its border."""
    u, v = np.meshgrid(np.linspace(0, width, side), np.linspace(0, width, side))
    z = height * np.sin(np.pi * u / width) * np.sin(np.pi * v / width)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        np.stack([u.ravel(), v.ravel(), z.ravel()], 1),
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        name="dome",
    )


def wall_x0(width: float = 1000.0) -> tgsis.Surface:
    """The vertical plane x = 0, larger than the dome's west side."""
    return tgsis.Surface(
        [[0, -width, -width], [0, 2 * width, -width], [0, 2 * width, 2 * width], [0, -width, 2 * width]],
        [[0, 1, 2], [0, 2, 3]],
        name="west wall",
    )


def test_a_dome_interpolated_to_itself_with_one_attached_border_vertex_stays_the_dome() -> None:
    """The issue's case: source = target, four corner controls, one west-side vertex attached to x = 0."""
    side = 21
    dome = dome_grid(side)
    corners = (0, side - 1, side * side - 1, side * (side - 1))
    west_middle = (side // 2) * side  # (0, 500, 0): on the plane x = 0
    setup = InterpolationSetup(
        corners,
        corners,
        controlling_surfaces={"west": "west"},
        attachments=(Attachment(west_middle, ("west",)),),
        steps=5,
        tolerance=1.0,
    )
    result = interpolate(dome, dome, setup, 0.0, 1.0, name="dome", surfaces={"west": wall_x0()})
    for t in (0.0, 0.25, 0.5, 0.75, 1.0):
        shape = result.evolving.at(t)
        assert shape is not None
        assert shape.vertices[:, 2].max() > 299.999, f"the dome is {shape.vertices[:, 2].max():.3f} m high at t = {t}"
        assert np.abs(shape.vertices - dome.vertices).max() < 1e-9 * 1000, f"the dome moved at t = {t}"


# ---------------------------------------------------------------- the river scenario's situation

#: the river scenario's basement profile: linear between 101 nodes along x, so points set on it lie on its triangles
BASEMENT_X = np.linspace(0.0, 5000.0, 101)


def basement_z(x: np.ndarray) -> np.ndarray:
    return np.asarray(np.interp(x, BASEMENT_X, -300.0 + 20.0 * np.sin(BASEMENT_X / 900.0)))


def strip(x0: float, x1: float, nx: int, ny: int, length: float = 2000.0) -> tuple[np.ndarray, np.ndarray]:
    u, v = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(0, length, ny))
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return np.stack([u.ravel(), v.ravel()], 1), np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])


def eroded_unit(nx: int, ny: int) -> tgsis.Surface:
    """The river scenario's unit 1 from t = 2 on: 70 m thick between pinch-outs at x = 500 and 2800, a 25 m
    channel cut into it at x = 1500, on the basement; its pinch-out edges lie on the basement."""
    xy, triangles = strip(500.0, 2800.0, nx, ny)
    s = (xy[:, 0] - 500.0) / 2300.0
    profile = np.where((s > 0) & (s < 1), 70.0 * np.sin(np.pi * np.clip(s, 0, 1)) ** 0.7, 0.0)
    profile = np.maximum(profile - 25.0 * np.exp(-(((xy[:, 0] - 1500.0) / 300.0) ** 2)), 0.0)
    return tgsis.Surface(np.column_stack([xy, basement_z(xy[:, 0]) + profile]), triangles, name="unit 1")


@pytest.mark.parametrize(("nx", "ny"), [(25, 6), (61, 21)])
def test_a_unit_identical_at_two_instants_does_not_sag_between_them(nx: int, ny: int) -> None:
    """The river scenario's unit 1 is the same at t = 3 and t = 4, its pinch-out edges attached to the basement;
    it sagged 17 m (24 m at the large size) at t = 3.5."""
    xy, triangles = strip(0.0, 5000.0, len(BASEMENT_X), ny)
    floor = tgsis.Surface(np.column_stack([xy, basement_z(xy[:, 0])]), triangles, name="basement")
    unit = eroded_unit(nx, ny)
    corners = (0, nx - 1, nx * ny - 1, nx * (ny - 1))
    edges = [j * nx for j in range(1, ny - 1)] + [j * nx + nx - 1 for j in range(1, ny - 1)]
    assert np.abs(unit.vertices[edges, 2] - basement_z(unit.vertices[edges, 0])).max() == 0.0
    setup = InterpolationSetup(
        corners,
        corners,
        controlling_surfaces={"basement": "basement"},
        attachments=tuple(Attachment(v, ("basement",)) for v in edges),
        steps=4,
        tolerance=1.0,
    )
    result = interpolate(unit, unit, setup, 3.0, 4.0, name="unit 1", surfaces={"basement": floor})
    for t in np.linspace(3.0, 4.0, 9):
        shape = result.evolving.at(float(t))
        assert shape is not None
        assert np.abs(shape.vertices - unit.vertices).max() < 1e-9, f"unit 1 moved at t = {t}"
    on_floor = ControllingSurface(floor.vertices, floor.cells)
    assert on_floor.distance(result.trajectories[:, edges].reshape(-1, 3)).max() < 1e-9


# ---------------------------------------------------------------- properties (hypothesis)

PROPERTY = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@dataclass
class Sheet:
    """A bumpy grid sheet: vertices (n, 3), triangles, its border sides and corners, its size."""

    vertices: np.ndarray
    triangles: np.ndarray
    nx: int
    ny: int
    width: float

    @property
    def corners(self) -> list[int]:
        return [0, self.nx - 1, self.nx * self.ny - 1, self.nx * (self.ny - 1)]

    @property
    def west(self) -> list[int]:
        """The side x = min without its corners."""
        return [j * self.nx for j in range(1, self.ny - 1)]

    @property
    def border(self) -> list[int]:
        nx, ny = self.nx, self.ny
        return sorted({*range(nx), *range(nx * (ny - 1), nx * ny), *range(0, nx * ny, nx), *range(nx - 1, nx * ny, nx)})

    @property
    def interior(self) -> np.ndarray:
        mask = np.ones(len(self.vertices), dtype=bool)
        mask[self.border] = False
        return mask


def bumps(rng: np.random.Generator, xy: np.ndarray, width: float, count: int) -> np.ndarray:
    """A sum of ``count`` smooth Gaussian bumps, heights up to half the width, widths 0.15..0.5 of it."""
    z = np.zeros(len(xy))
    for _ in range(count):
        centre = rng.uniform(0, width, 2)
        spread = rng.uniform(0.15, 0.5) * width
        z += rng.uniform(-0.5, 0.5) * width * np.exp(-((xy - centre) ** 2).sum(axis=1) / (2 * spread**2))
    return z


@st.composite
def sheets(draw: st.DrawFn) -> tuple[Sheet, np.random.Generator]:
    """A grid of 4..11 x 4..11 vertices over a square of 1 m..5 km, jittered in plan, each quad's diagonal
    drawn, with 1..3 random smooth bumps; and the generator that drew it (for what the test draws next)."""
    nx, ny = draw(st.integers(4, 11)), draw(st.integers(4, 11))
    width = draw(st.sampled_from([1.0, 37.5, 1000.0, 5000.0]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    u, v = np.meshgrid(np.linspace(0, width, nx), np.linspace(0, width, ny))
    xy = np.stack([u.ravel(), v.ravel()], 1)
    inner = np.ones((ny, nx), dtype=bool)
    inner[[0, -1], :] = inner[:, [0, -1]] = False
    xy[inner.ravel()] += rng.uniform(-0.2, 0.2, (int(inner.sum()), 2)) * width / max(nx, ny)
    idx = np.arange(nx * ny).reshape(ny, nx)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    flip = rng.random(len(a)) < 0.5
    first = np.where(flip[:, None], np.stack([a, b, c], 1), np.stack([a, b, d], 1))
    second = np.where(flip[:, None], np.stack([b, d, c], 1), np.stack([a, d, c], 1))
    z = bumps(rng, xy, width, int(rng.integers(1, 4)))
    return Sheet(np.column_stack([xy, z]), np.concatenate([first, second]), nx, ny, width), rng


def plane_through(point: np.ndarray, normal: np.ndarray, half: float, name: str) -> ControllingSurface:
    """A square of the plane through ``point`` with ``normal``, 2 * half wide, centred on the point."""
    normal = normal / np.linalg.norm(normal)
    e1 = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(normal, e1)
    square = [point + half * (i * e1 + j * e2) for i, j in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
    return ControllingSurface(square, [[0, 1, 2], [0, 2, 3]], name=name)


def random_attachments(
    sheet: Sheet,
    rng: np.random.Generator,
    along: np.ndarray | None = None,
) -> dict[int, list[ControllingSurface]]:
    """A random non-empty set of border vertices, each on a plane of random orientation through it (containing
    the direction ``along`` when given); corners may take two such planes (their intersection line)."""
    border = np.asarray(sheet.border)
    chosen = rng.choice(border, size=int(rng.integers(1, len(border) + 1)), replace=False)
    half = 4.0 * (sheet.width + np.abs(sheet.vertices).max() + (0.0 if along is None else np.linalg.norm(along)))

    def normal() -> np.ndarray:
        n = rng.normal(size=3)
        if along is not None:
            n -= n @ along / (along @ along) * along
        return n

    result: dict[int, list[ControllingSurface]] = {}
    for vertex in chosen.tolist():
        point = sheet.vertices[vertex]
        planes = [plane_through(point, normal(), half, f"plane {vertex}")]
        if vertex in sheet.corners and rng.random() < 0.5:
            planes.append(plane_through(point, normal(), half, f"second plane {vertex}"))
        result[vertex] = planes
    return result


def scale_of(*points: np.ndarray) -> float:
    both = np.concatenate(points)
    return float(np.linalg.norm(both.max(axis=0) - both.min(axis=0)))


@PROPERTY
@given(drawn=sheets(), steps=st.integers(2, 9))
def test_identity_is_exact_at_every_step_with_any_attachment(
    drawn: tuple[Sheet, np.random.Generator], steps: int
) -> None:
    sheet, rng = drawn
    attachments = random_attachments(sheet, rng)
    paths = vertex_trajectories(
        sheet.vertices, sheet.vertices, sheet.triangles, steps, attachments, controls=sheet.corners
    )
    # every sample is the surface itself, to rounding (the planes' closest points are the only rounding)
    assert np.abs(paths - sheet.vertices[None]).max() <= 1e-12 * scale_of(sheet.vertices)
    assert np.array_equal(paths[0], sheet.vertices) and np.array_equal(paths[-1], sheet.vertices)


@PROPERTY
@given(drawn=sheets(), steps=st.integers(2, 9), shift=st.tuples(*[st.floats(-2.0, 2.0)] * 3))
def test_a_translated_copy_moves_rigidly(
    drawn: tuple[Sheet, np.random.Generator], steps: int, shift: tuple[float, float, float]
) -> None:
    """The attached vertices' planes contain the translation, so that they are on them at both ends."""
    sheet, rng = drawn
    move = np.asarray(shift) * sheet.width
    assume(np.linalg.norm(move) > 1e-3 * sheet.width)
    target = sheet.vertices + move
    attachments = random_attachments(sheet, rng, along=move)
    paths = vertex_trajectories(sheet.vertices, target, sheet.triangles, steps, attachments, controls=sheet.corners)
    s = np.arange(steps) / (steps - 1)
    expected = sheet.vertices[None] + s[:, None, None] * move
    assert np.abs(paths - expected).max() <= 1e-12 * scale_of(sheet.vertices, target)
    assert np.array_equal(paths[0], sheet.vertices) and np.array_equal(paths[-1], target)


@dataclass
class CurvedWall:
    """The wall x = -bend * width * ((z - middle) / span)^2, a cylinder along y over the heights [low, high] with
    margins, triangulated linearly in z between its nodes, so that (x_at(z), y, z) lies on its triangles. Its
    triangles are kept well shaped (rows in y as far apart as the nodes in z): closest points on slivers lose
    digits, which is the projection's rounding, not the interpolation's."""

    width: float
    low: float
    high: float
    bend: float

    @property
    def nodes(self) -> np.ndarray:
        margin = max(self.high - self.low, 0.5 * self.width)
        return np.linspace(self.low - margin, self.high + margin, 41)

    def x_at(self, z: np.ndarray) -> np.ndarray:
        nodes = self.nodes
        middle, span = (self.low + self.high) / 2, nodes[-1] - nodes[0]
        return np.asarray(np.interp(z, nodes, -self.bend * self.width * ((nodes - middle) / span) ** 2))

    def surface(self) -> ControllingSurface:
        z = self.nodes
        rows = max(2, int(np.ceil(3 * self.width / (z[1] - z[0]))) + 1)
        zz, yy = np.meshgrid(z, np.linspace(-self.width, 2 * self.width, rows))
        vertices = np.column_stack([self.x_at(zz.ravel()), yy.ravel(), zz.ravel()])
        idx = np.arange(rows * 41).reshape(rows, 41)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
        return ControllingSurface(
            vertices, np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]), name="curved wall"
        )


@st.composite
def relief_pairs(draw: st.DrawFn) -> tuple[Sheet, np.ndarray, float, ControllingSurface]:
    """A bumpy sheet and its target: the bumps scaled by alpha in 0.2..3 and lifted; the west side of both on a
    curved wall (so that the straight paths of its vertices leave the wall and are projected back onto it)."""
    sheet, rng = draw(sheets())
    alpha = draw(st.floats(0.2, 3.0))
    bend = draw(st.floats(0.0, 2.0))
    lift = draw(st.floats(-1.0, 1.0)) * sheet.width
    target = sheet.vertices.copy()
    target[:, 2] = alpha * sheet.vertices[:, 2] + lift
    heights = np.concatenate([sheet.vertices[:, 2], target[:, 2]])
    low, high = float(heights.min()), float(heights.max())
    west = sheet.west
    wall = CurvedWall(sheet.width, low, high, bend)
    sheet.vertices[west, 0] = wall.x_at(sheet.vertices[west, 2])
    target[west, 0] = wall.x_at(target[west, 2])
    return sheet, target, alpha, wall.surface()


@PROPERTY
@given(pair=relief_pairs(), steps=st.integers(3, 9))
def test_smooth_bumps_keep_their_relief_within_the_border_departure(
    pair: tuple[Sheet, np.ndarray, float, ControllingSurface], steps: int
) -> None:
    """The bound (docs/interpolation.md): at every instant, every vertex is within D of its straight path, D the
    largest distance by which a controlling surface moves a border vertex off its own straight path then; so the
    relief (height range) is within 2 D_z of the straight blend's, here (1 - s + s alpha) times the source's."""
    sheet, target, alpha, wall = pair
    west = sheet.west
    paths = vertex_trajectories(
        sheet.vertices, target, sheet.triangles, steps, {v: [wall] for v in west}, controls=sheet.corners
    )
    scale = scale_of(sheet.vertices, target)
    rounding = 1e-11 * scale
    s = np.arange(steps) / (steps - 1)
    straight = sheet.vertices[None] + s[:, None, None] * (target - sheet.vertices)[None]
    departure = paths - straight  # (m, n, 3)
    border_departure = np.linalg.norm(departure[:, sheet.border], axis=2).max(axis=1)
    border_departure_z = np.abs(departure[:, sheet.border, 2]).max(axis=1)
    relief = np.ptp(sheet.vertices[:, 2])
    for j in range(steps):
        assert np.linalg.norm(departure[j], axis=1).max() <= border_departure[j] + rounding
        assert abs(np.ptp(paths[j, :, 2]) - (1 - s[j] + s[j] * alpha) * relief) <= 2 * border_departure_z[j] + rounding
    # the attached vertices stay on the wall: projected onto it in between (to rounding), where they were given at
    # the ends (the given positions, on the wall to within the rounding of this test's set-up)
    assert wall.distance(paths[1:-1, west].reshape(-1, 3)).max(initial=0.0) <= 1e-12 * wall.scale
    assert np.array_equal(paths[0, west], sheet.vertices[west]) and np.array_equal(paths[-1, west], target[west])
    # unattached border vertices (the corners, the control vertices, among them) keep their straight paths
    free = np.setdiff1d(sheet.border, west)
    assert np.abs(departure[:, free]).max() <= rounding


@PROPERTY
@given(pair=relief_pairs(), steps=st.integers(3, 9))
def test_the_differential_coordinates_go_linearly_in_time(
    pair: tuple[Sheet, np.ndarray, float, ControllingSurface], steps: int
) -> None:
    """What the solve means, checked from the public weights: with Λ̄ the mean of the two meshes' mean value
    weights, (I - Λ̄) x(s) on interior vertices is (1 - s) (I - Λ̄) x^1 + s (I - Λ̄) x^m."""
    sheet, target, _, wall = pair
    paths = vertex_trajectories(sheet.vertices, target, sheet.triangles, steps, {v: [wall] for v in sheet.west})
    lam = 0.5 * (mean_value_weights(sheet.vertices, sheet.triangles) + mean_value_weights(target, sheet.triangles))
    inside = sheet.interior

    def delta(x: np.ndarray) -> np.ndarray:
        return np.asarray((x - lam @ x)[inside])

    first, last = delta(sheet.vertices), delta(target)
    scale = scale_of(sheet.vertices, target)
    for j, s in enumerate(np.arange(steps) / (steps - 1)):
        assert np.abs(delta(paths[j]) - ((1 - s) * first + s * last)).max() <= 1e-11 * scale


@PROPERTY
@given(pair=relief_pairs(), steps=st.integers(2, 9))
def test_swapping_source_and_target_reverses_the_trajectories(
    pair: tuple[Sheet, np.ndarray, float, ControllingSurface], steps: int
) -> None:
    """The source may be the earlier or the later shape: the evolving surface is the same."""
    sheet, target, _, wall = pair
    attachments = {v: [wall] for v in sheet.west}
    forward = vertex_trajectories(sheet.vertices, target, sheet.triangles, steps, attachments)
    backward = vertex_trajectories(target, sheet.vertices, sheet.triangles, steps, attachments)
    assert np.abs(forward - backward[::-1]).max() <= 1e-11 * scale_of(sheet.vertices, target)


# ---------------------------------------------------------------- one factorisation, closed parts


def test_one_factorisation_serves_every_step(monkeypatch: pytest.MonkeyPatch) -> None:
    side = 15
    dome = dome_grid(side)
    target = dome.vertices.copy()
    target[:, 2] *= 0.5
    west = [j * side for j in range(1, side - 1)]
    calls: list[int] = []
    from scipy.sparse.linalg import splu as real  # what trajectories imports

    def counted(*args: object, **kwargs: object) -> object:
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(trajectories, "splu", counted)
    wall = ControllingSurface(wall_x0().vertices, wall_x0().cells, name="wall")
    paths = vertex_trajectories(dome.vertices, target, dome.cells, 12, {v: [wall] for v in west})
    assert len(calls) == 1
    assert np.array_equal(paths[0], dome.vertices) and np.array_equal(paths[-1], target)
    system = trajectories.InteriorSteps(dome.vertices, target, dome.cells, interior_mask(dome.cells, len(target)))
    assert system.factorizations == 1 and len(calls) == 2
    assert np.abs(paths[5, system.interior] - system.solve([5 / 11], paths[5:6, system.border])[0]).max() == 0.0


def test_a_closed_part_without_border_keeps_its_straight_paths() -> None:
    """A disk with attachments beside a closed tetrahedron: nothing constrains the tetrahedron (its system alone
    would be singular), so its vertices go straight; the disk is solved as usual."""
    side = 9
    dome = dome_grid(side)
    tetra = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]) * 100 + [3000, 0, 0]
    n = dome.n_vertices
    vertices = np.concatenate([dome.vertices, tetra])
    triangles = np.concatenate([dome.cells, n + np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])])
    target = vertices.copy()
    target[n:] += [50.0, 20.0, -10.0]
    wall = ControllingSurface(wall_x0().vertices, wall_x0().cells, name="wall")
    west = [j * side for j in range(1, side - 1)]
    paths = vertex_trajectories(vertices, target, triangles, 5, {v: [wall] for v in west})
    s = np.arange(5) / 4
    assert np.abs(paths[:, n:] - (vertices[n:] + s[:, None, None] * (target[n:] - vertices[n:]))).max() < 1e-12
    assert np.abs(paths[:, :n] - dome.vertices).max() < 1e-9


def test_a_dome_split_by_a_fence_stays_the_dome_either_way_in_time() -> None:
    """Two patches stitched along a fence across the dome's top (fence vertices are interior to the whole mesh,
    solved with the rest), both west and east sides attached to walls, the later time given first."""
    side = 21
    dome = dome_grid(side)
    middle = side // 2
    controls = (0, middle, side - 1, side * side - 1, side * (side - 1) + middle, side * (side - 1))
    fence = tuple(middle + side * j for j in range(side))
    west = [j * side for j in range(1, side - 1)]
    east = [j * side + side - 1 for j in range(1, side - 1)]
    east_wall = tgsis.Surface(wall_x0().vertices + [1000.0, 0, 0], wall_x0().cells, name="east wall")
    setup = InterpolationSetup(
        controls,
        controls,
        source_fences=(fence,),
        target_fences=(fence,),
        controlling_surfaces={"west": "west", "east": "east"},
        attachments=tuple(Attachment(v, ("west",)) for v in west) + tuple(Attachment(v, ("east",)) for v in east),
        steps=6,
        tolerance=1.0,
    )
    result = interpolate(dome, dome, setup, 2.0, 1.0, surfaces={"west": wall_x0(), "east": east_wall})
    assert np.abs(result.target.vertices - dome.vertices).max() < 1e-9  # the compatible target is the dome
    for t in np.linspace(1.0, 2.0, 11):
        shape = result.evolving.at(float(t))
        assert shape is not None
        assert np.abs(shape.vertices - dome.vertices).max() < 1e-9, f"the dome moved at t = {t}"


def test_a_lifted_dome_moves_rigidly_through_interpolate() -> None:
    """The dome and a copy 120 m higher and 40 m north (parallel to the west wall, so the attached west side stays on
    it): every instant is the dome moved by the same fraction of the shift."""
    side = 21
    dome = dome_grid(side)
    shift = np.array([0.0, 40.0, 120.0])
    lifted = tgsis.Surface(dome.vertices + shift, dome.cells, name="lifted")
    corners = (0, side - 1, side * side - 1, side * (side - 1))
    west = [j * side for j in range(1, side - 1)]
    setup = InterpolationSetup(
        corners,
        corners,
        controlling_surfaces={"west": "west"},
        attachments=tuple(Attachment(v, ("west",)) for v in west),
        steps=5,
        tolerance=1.0,
    )
    result = interpolate(dome, lifted, setup, 0.0, 1.0, surfaces={"west": wall_x0()})
    for t in np.linspace(0.0, 1.0, 9):
        shape = result.evolving.at(float(t))
        assert shape is not None
        assert np.abs(shape.vertices - (dome.vertices + t * shift)).max() < 1e-9, f"not rigid at t = {t}"
