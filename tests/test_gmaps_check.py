"""GMap.check: every condition broken on purpose, with the offending darts named (no database)."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt
import pytest

import tgsis
from tests import gmaps_shapes as shapes
from tgsis.gmaps import GMap

IntArray = npt.NDArray[np.int64]


def octahedron_map() -> GMap:
    return GMap.from_triangles(*shapes.octahedron())


def edited(g: GMap, **changes: IntArray) -> GMap:
    return GMap(changes.get("alpha", g.alpha), changes.get("vertex", g.vertex), g.points)


def reference(alpha: IntArray) -> dict[str, object]:
    """The conditions checked dart by dart in plain Python."""
    n = len(alpha) - 1
    d = alpha.shape[1]
    return {
        "not_involutions": {i: [x for x in range(d) if alpha[i, alpha[i, x]] != x] for i in range(n + 1)},
        "fixed_points": {i: [x for x in range(d) if alpha[i, x] == x] for i in range(n)},
        "compositions": {
            (i, j): [x for x in range(d) if alpha[i, alpha[j, alpha[i, alpha[j, x]]]] != x]
            for i in range(n + 1)
            for j in range(i + 2, n + 1)
        },
    }


def nonempty(found: Mapping[int, IntArray]) -> dict[int, list[int]]:
    return {k: v.tolist() for k, v in found.items()}


def expected(ref: dict[object, list[int]]) -> dict[object, list[int]]:
    return {k: v for k, v in ref.items() if v}


def test_valid_maps_pass() -> None:
    for g in (octahedron_map(), GMap.from_tetrahedra(*shapes.cube_tetrahedra())):
        report = g.check()
        assert report.ok and report.problems() == [] and report.summary() == "a valid G-map"
        assert g.check(raise_=True) == report


def test_not_an_involution() -> None:
    g = octahedron_map()
    alpha = g.alpha.copy()
    x, y = 0, int(alpha[2, 0])
    z = int(alpha[2, 7])
    alpha[2, x] = z  # x -> z, but z -> 7 and y -> x
    report = edited(g, alpha=alpha).check()
    ref = reference(alpha)
    assert nonempty(report.not_involutions) == expected(ref["not_involutions"])  # type: ignore[arg-type]
    assert report.not_involutions[2].tolist() == sorted([x, y])  # z -> 7 -> z still holds
    assert f"alpha2 is not an involution at darts {', '.join(map(str, report.not_involutions[2]))}" in report.problems()
    with pytest.raises(
        tgsis.InvalidGMapError, match=r"not a valid 2-G-map: alpha2 is not an involution at darts 0"
    ) as err:
        edited(g, alpha=alpha).check(raise_=True)
    assert err.value.sqlstate == "TG104" and isinstance(err.value, tgsis.InvalidGeometryError)


def test_fixed_point_below_the_top_involution() -> None:
    g = octahedron_map()
    alpha = g.alpha.copy()
    x = 9
    y = int(alpha[1, x])
    alpha[1, x], alpha[1, y] = x, y  # still an involution, but alpha1 now leaves two darts free
    report = edited(g, alpha=alpha).check()
    assert nonempty(report.fixed_points) == {1: sorted([x, y])}
    assert report.not_involutions == {}
    assert f"alpha1 has fixed points (only alpha2 may) at darts {min(x, y)}, {max(x, y)}" in report.problems()
    # free darts in alpha2 are the border, not an error
    top = g.alpha.copy()
    u, v = 3, int(top[2, 3])
    top[2, u], top[2, v] = u, v
    assert edited(g, alpha=top).check().fixed_points == {}


def resewn(alpha: IntArray, top: int, x: int, z: int) -> IntArray:
    """alpha with the top involution's partners of darts x and z exchanged (both still involutions)."""
    out = alpha.copy()
    y, w = int(alpha[top, x]), int(alpha[top, z])
    out[top, x], out[top, w] = w, x
    out[top, z], out[top, y] = y, z
    return out


def test_broken_composition() -> None:
    g = octahedron_map()
    # dart 1 sewn to the partner of dart 30 (another edge): alpha0 o alpha2 no longer an involution there
    alpha = resewn(g.alpha, 2, 1, 30)
    report = edited(g, alpha=alpha).check()
    assert report.not_involutions == {} and report.fixed_points == {}
    ref = reference(alpha)
    assert nonempty(report.not_involutive_compositions) == expected(ref["compositions"])  # type: ignore[arg-type]
    assert 1 in report.not_involutive_compositions[(0, 2)]
    assert any(p.startswith("alpha0 o alpha2 is not an involution at darts") for p in report.problems())


def test_broken_compositions_in_a_3_map() -> None:
    g = GMap.from_tetrahedra(*shapes.block_tetrahedra(1))
    inner = np.flatnonzero(g.alpha[3] != np.arange(g.n_darts))
    alpha = resewn(g.alpha, 3, int(inner[0]), int(inner[-1]))
    report = edited(g, alpha=alpha).check()
    ref = reference(alpha)
    assert nonempty(report.not_involutive_compositions) == expected(ref["compositions"])  # type: ignore[arg-type]
    assert {(0, 3), (1, 3)} <= set(report.not_involutive_compositions)
    assert int(inner[0]) in report.not_involutive_compositions[(1, 3)]


def test_darts_of_one_vertex_on_two_points() -> None:
    g = octahedron_map()
    vertex = g.vertex.copy()
    vertex[4] = (vertex[4] + 1) % 6
    report = edited(g, vertex=vertex).check()
    a = g.alpha
    assert nonempty(report.split_vertices) == {1: sorted([4, int(a[1, 4])]), 2: sorted([4, int(a[2, 4])])}
    assert "darts joined by alpha1 have different vertices" in report.summary()


def test_topology_periods() -> None:
    one = octahedron_map()
    d = one.n_darts
    two = GMap(np.concatenate([one.alpha, one.alpha + d], axis=1), np.concatenate([one.vertex, one.vertex]), one.points)
    periods = np.repeat([0, 1], d)
    assert two.check(periods).ok
    periods[5] = 1  # one dart of the first object said to be in the second period
    report = two.check(periods)
    a = two.alpha
    assert nonempty(report.crossing_periods) == {i: sorted([5, int(a[i, 5])]) for i in range(3)}
    assert "alpha0 joins darts of different topology periods at darts" in report.summary()
    with pytest.raises(tgsis.InvalidGMapError, match="topology periods"):
        two.check(periods, raise_=True)
    # a dart sewn across periods (alpha2 from the first object into the second)
    alpha = two.alpha.copy()
    x, y = 0, int(alpha[2, 0])
    u, v = d, int(alpha[2, d])
    alpha[2, x], alpha[2, u] = u, x
    alpha[2, y], alpha[2, v] = v, y
    crossing = GMap(alpha, two.vertex, two.points).check(np.repeat([0, 1], d)).crossing_periods
    assert nonempty(crossing) == {2: sorted([x, y, u, v])}


@pytest.mark.parametrize("periods", [np.zeros(3, dtype=np.int64), np.zeros(48), np.zeros((48, 1), dtype=np.int64)])
def test_bad_periods(periods: IntArray) -> None:
    with pytest.raises(tgsis.InvalidInputError, match=r"periods must be one integer per dart, shape \(48,\)"):
        octahedron_map().check(periods)


def test_many_darts_are_named_briefly() -> None:
    g = octahedron_map()
    alpha = g.alpha.copy()
    alpha[0] = np.arange(g.n_darts)  # alpha0 free everywhere
    problem = edited(g, alpha=alpha).check().problems()
    assert "at darts 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, ... (48 in all)" in problem[0]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            (np.zeros((3, 4), dtype=np.int64) + [0, 1, 2, 7], np.zeros(4, dtype=np.int64), np.zeros((1, 2))),
            "alpha0 sends dart 3 to 7, but the map has 4 darts",
        ),
        ((np.zeros((0, 4), dtype=np.int64), np.zeros(4, dtype=np.int64), np.zeros((1, 2))), "n \\+ 1 >= 1 rows"),
        ((np.zeros((2, 2)), np.zeros(2, dtype=np.int64), np.zeros((1, 2))), "alpha must be integers"),
        (
            (np.array([[1, 0], [0, 1]]), np.zeros(3, dtype=np.int64), np.zeros((1, 2))),
            "one point index per dart: 3 for 2 darts",
        ),
        (
            (np.array([[1, 0], [0, 1]]), np.array([0, 2]), np.zeros((2, 2))),
            "dart 1 has vertex 2, but there are 2 points",
        ),
        (
            (np.array([[1, 0], [0, 1]]), np.array([0, 1]), [[0, 0], [np.inf, 0]]),
            "point 1 has a non-finite coordinate 0",
        ),
        ((np.array([[1, 0], [0, 1]]), np.array([0, 1]), np.zeros(2)), r"points must be a \(k, m\) array"),
    ],
)
def test_unreadable_arrays(args: tuple[object, object, object], message: str) -> None:
    with pytest.raises(tgsis.InvalidGMapError, match=message):
        GMap(*args)  # type: ignore[arg-type]


def test_border_of_a_broken_map_is_refused() -> None:
    g = GMap.from_triangles(*shapes.grid(2, 2))
    alpha = g.alpha.copy()
    free = g.border_darts()
    alpha[0, free[0]] = int(np.setdiff1d(np.arange(g.n_darts), free)[0])  # alpha0 leads off the border
    with pytest.raises(tgsis.InvalidGMapError, match="the border cannot be built"):
        GMap(alpha, g.vertex, g.points).border()
