"""Deposition in the library (issue 37, part 2): a unit grows from the surface beneath; younger lies above older.

Pure numpy: :func:`tgsis.deposit`, :func:`tgsis.drape`, :func:`tgsis.keep_above`
and the contact they report, on curved surfaces and meshes that do not
share vertices.
"""

from __future__ import annotations

import numpy as np
import pytest

import tgsis
from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.interpolation import InterpolationSetup, deposit, drape, heights_below, keep_above
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, TopologyPeriod

SIDE = 1000.0


def grid(n: int, z: object = None, x0: float = 0.0, x1: float = SIDE) -> Surface:
    """An n x n grid over [x0, x1] x [0, SIDE]; z(x, y) or 0; corners 0, n-1, n*n-1, n*(n-1)."""
    u, v = np.meshgrid(np.linspace(x0, x1, n), np.linspace(0.0, SIDE, n))
    idx = np.arange(n * n).reshape(n, n)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    x, y = u.ravel(), v.ravel()
    height = np.zeros_like(x) if z is None else np.asarray(z(x, y), dtype=np.float64)  # type: ignore[operator]
    return Surface(np.column_stack([x, y, height]), np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]))


def corners(n: int) -> tuple[int, ...]:
    return (0, n - 1, n * n - 1, n * (n - 1))


def floor_z(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A curved older surface: a ridge and a tilt (not a plane, not a membrane)."""
    return 60.0 * np.sin(x / 250.0) + 0.05 * y - 200.0


def lens(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """A unit's thickness: 0 on the border, 40 m in the middle."""
    return 40.0 * np.sin(np.pi * x / SIDE) * np.sin(np.pi * y / SIDE)


def test_heights_below_takes_the_highest_surface_and_says_which() -> None:
    low, high = grid(5, lambda x, y: 0.1 * x), grid(5, lambda x, y: 0.1 * x + 10.0, 0.0, 500.0)
    points = np.array([[100.0, 100.0], [700.0, 300.0], [1500.0, 10.0]])
    z, which = heights_below(points, [low, None, high])
    assert z[0] == pytest.approx(20.0) and which[0] == 2  # both reach it: the higher one
    assert z[1] == pytest.approx(70.0) and which[1] == 0  # only the lower one reaches it
    assert np.isnan(z[2]) and which[2] == -1  # none does


def test_heights_below_skips_a_vertical_triangle() -> None:
    wall = Surface([[0, 0, 0], [0, 10, 0], [0, 0, 10]], [[0, 1, 2]])
    z, which = heights_below([[0.0, 5.0]], [wall])
    assert which.tolist() == [-1] and np.isnan(z).all()


def test_drape_puts_every_vertex_on_the_highest_older_surface() -> None:
    top = grid(9, lambda x, y: floor_z(x, y) + lens(x, y))
    basement = grid(40, floor_z)
    bump = grid(6, lambda x, y: floor_z(x, y) + 30.0, 0.0, 400.0)
    draped = drape(top, [basement, bump])
    expected, _ = heights_below(top.vertices, [basement, bump])
    np.testing.assert_array_equal(draped.vertices[:, 2], expected)
    np.testing.assert_array_equal(draped.vertices[:, :2], top.vertices[:, :2])
    np.testing.assert_array_equal(draped.cells, top.cells)
    left = top.vertices[:, 0] < 350
    assert np.all(draped.vertices[left, 2] > floor_z(top.vertices[left, 0], top.vertices[left, 1]) + 29)


def test_drape_refuses_a_vertex_with_nothing_beneath() -> None:
    top = grid(5, x0=0.0, x1=2000.0)
    with pytest.raises(InvalidGeometryError, match=r"10 of 25 vertices .* no older surface") as caught:
        drape(top, [grid(5)])
    assert "basement" in (caught.value.hint or "")


def test_a_deposited_unit_starts_on_the_curved_surface_beneath_and_thickens() -> None:
    """The design's order: source = the top at t2, target = the older surface at t1 (another mesh)."""
    top = grid(13, lambda x, y: floor_z(x, y) + lens(x, y))
    top.name = "unit"
    beneath = grid(31, floor_z)
    setup = InterpolationSetup(corners(13), corners(31), steps=5, tolerance=2.0)
    result = deposit(top, beneath, setup, 1.0, 2.0, alive=True)
    unit = result.evolving
    assert (unit.start, unit.end, unit.name, unit.alive) == (1.0, 2.0, "unit", True)
    assert unit.at(0.5) is None  # nothing before its deposition
    first = unit.at(1.0)
    assert first is not None
    under, which = heights_below(first.vertices, [beneath])
    assert (which == 0).all()
    np.testing.assert_allclose(first.vertices[:, 2], under, atol=1e-9)  # on the surface beneath, exactly
    assert result.settled < 1e-6  # the compatible target was on it already
    last = unit.at(2.0)
    assert last is not None
    np.testing.assert_array_equal(last.vertices, top.vertices)  # its top at t2
    means = []
    for t in np.linspace(1.0, 2.0, 21):
        shape = unit.at(float(t))
        assert shape is not None
        floor, _ = heights_below(shape.vertices, [beneath])
        thickness = shape.vertices[:, 2] - floor
        assert thickness.min() > -1.0, t  # within the floor's chord error
        means.append(float(thickness.mean()))
    assert means[0] == pytest.approx(0.0, abs=1e-9)
    assert all(b > a for a, b in zip(means, means[1:]))  # it thickens
    assert means[10] == pytest.approx(means[-1] / 2, rel=0.05)  # linearly
    assert result.interpolation.target.n_vertices == first.n_vertices


def test_a_unit_deposited_on_several_older_surfaces_starts_on_the_highest() -> None:
    basement = grid(30, floor_z)
    older = grid(7, lambda x, y: floor_z(x, y) + 25.0 * np.sin(np.pi * x / 400.0) ** 2, 0.0, 400.0)
    top = grid(11, lambda x, y: heights_below(np.column_stack([x, y]), [basement, older])[0] + lens(x, y))
    setup = InterpolationSetup(corners(11), corners(11), steps=4)
    result = deposit(top, [basement, older], setup, 0.0, 3.0)
    first = result.evolving.at(0.0)
    assert first is not None
    floor, which = heights_below(first.vertices, [basement, older])
    np.testing.assert_allclose(first.vertices[:, 2], floor, atol=1e-9)
    assert set(which.tolist()) == {0, 1}  # partly on each
    with pytest.raises(InvalidInputError, match="target controls must be the source controls"):
        deposit(top, [basement], InterpolationSetup(corners(11), (1, 9, 119, 111)), 0.0, 3.0)


@pytest.mark.parametrize(("start", "end"), [(2.0, 1.0), (1.0, 1.0), (float("nan"), 1.0), (0.0, float("inf"))])
def test_a_deposition_runs_forward_in_time(start: float, end: float) -> None:
    top = grid(5, lambda x, y: lens(x, y))
    with pytest.raises(InvalidInputError, match="later end"):
        deposit(top, grid(5), InterpolationSetup(corners(5), corners(5)), start, end)


def _evolving(times: list[float], shapes: list[np.ndarray], surface: Surface, name: str) -> EvolvingSurface:
    return EvolvingSurface([TopologyPeriod(times, surface.cells, np.stack(shapes))], name=name)


def test_keep_above_raises_what_dips_below_and_reports_the_contact() -> None:
    base = grid(11)
    older = EvolvingSurface.constant(grid(21, lambda x, y: 0.01 * x), 0.0, 2.0, name="older")  # other vertices
    start = base.vertices.copy()
    start[:, 2] = 0.01 * start[:, 0] + 5.0
    end = start.copy()
    east = base.vertices[:, 0] > 500
    end[east, 2] -= 20.0  # 15 m below the older surface at t = 2
    younger = _evolving([0.0, 2.0], [start, end], base, "younger")
    stacking = keep_above(younger, [older])
    (contact,) = stacking.contacts
    np.testing.assert_array_equal(contact.times, [0.0, 2.0])
    np.testing.assert_allclose(contact.raised[1, east], 15.0)
    assert not contact.raised[1, ~east].any() and not contact.raised[0].any()
    assert (contact.lies_on[1] == np.where(east, 0, -1)).all() and (contact.lies_on[0] == -1).all()
    assert stacking.max_raise == pytest.approx(15.0) and stacking.clamped == int(east.sum())
    assert stacking.lies_on() == [0]
    kept = stacking.surface.at(2.0)
    assert kept is not None
    np.testing.assert_allclose(kept.vertices[east, 2], 0.01 * kept.vertices[east, 0])
    np.testing.assert_array_equal(kept.vertices[~east], end[~east])  # where it was above: untouched
    assert stacking.surface.name == "younger"
    # the input is not changed
    np.testing.assert_array_equal(younger.periods[0].positions[1], end)


def test_keep_above_adds_the_older_surfaces_instants() -> None:
    """An older surface that rises and falls between the younger's instants is honoured at its own instants."""
    base = grid(6)
    flat = base.vertices.copy()
    risen = flat.copy()
    risen[:, 2] = 8.0
    older = _evolving([0.0, 1.0, 2.0], [flat, risen, flat], base, "older")
    above = flat.copy()
    above[:, 2] = 3.0
    younger = _evolving([0.0, 2.0], [above, above], base, "younger")
    stacking = keep_above(younger, [older])
    np.testing.assert_array_equal(stacking.contacts[0].times, [0.0, 1.0, 2.0])
    for t in np.linspace(0.0, 2.0, 41):
        shape, under = stacking.surface.at(float(t)), older.at(float(t))
        assert shape is not None and under is not None
        assert (shape.vertices[:, 2] >= under.vertices[:, 2] - 1e-12).all(), t
    assert stacking.max_raise == pytest.approx(5.0)


def test_keep_above_ignores_an_older_surface_that_does_not_exist_then() -> None:
    base = grid(5)
    high = base.vertices.copy()
    high[:, 2] = 50.0
    later = EvolvingSurface([TopologyPeriod([1.0, 2.0], base.cells, np.stack([high, high]))])
    younger = _evolving([0.0, 0.5], [base.vertices, base.vertices], base, "younger")
    stacking = keep_above(younger, [later])
    assert stacking.clamped == 0 and stacking.contacts[0].times.tolist() == [0.0, 0.5]


def test_keep_above_keeps_consecutive_periods_sharing_their_shape() -> None:
    base = grid(7)
    a, b, c = base.vertices.copy(), base.vertices.copy(), base.vertices.copy()
    a[:, 2], b[:, 2], c[:, 2] = 10.0, -5.0 + 0.01 * b[:, 0], 10.0
    younger = EvolvingSurface.chain(
        [_evolving([0.0, 1.0], [a, b], base, "u"), _evolving([1.0, 2.0], [b, c], base, "u")]
    )
    stacking = keep_above(younger, [grid(4)])  # a constant Surface: z = 0
    first, second = stacking.surface.periods
    np.testing.assert_array_equal(first.positions[-1], second.positions[0])
    assert (first.positions[-1][:, 2] >= 0).all() and stacking.max_raise == pytest.approx(5.0)
    assert [c.period for c in stacking.contacts] == [0, 1]


@pytest.mark.parametrize("tolerance", [-1.0, float("nan")])
def test_keep_above_refuses_a_bad_tolerance(tolerance: float) -> None:
    base = grid(3)
    with pytest.raises(InvalidInputError, match="tolerance"):
        keep_above(EvolvingSurface.constant(base, 0.0, 1.0), [base], tolerance=tolerance)


def test_the_deposition_api_is_public() -> None:
    names = ["deposit", "Deposition", "drape", "keep_above", "Stacking", "Contact"]
    assert [n for n in names if n not in tgsis.__all__] == []
    assert tgsis.deposit is deposit and tgsis.keep_above is keep_above


def test_keep_above_adds_instants_where_a_vertex_would_dip_between_two() -> None:
    """A vertex sliding across a ridge is on it at both instants but would cut through it on the straight way."""
    ridge = grid(41, lambda x, y: 100.0 * np.sin(np.pi * x / SIDE))
    base = grid(3, x0=0.0, x1=10.0)
    west, east = base.vertices.copy(), base.vertices.copy()
    east[:, 0] += SIDE - 10.0
    west[:, 2], east[:, 2] = -1.0, -1.0
    younger = _evolving([0.0, 1.0], [west, east], base, "sliding")
    stacking = keep_above(younger, [ridge], between=0.01)
    assert 0.0 < stacking.residual <= 0.01 or stacking.residual <= 0.0
    assert len(stacking.surface.periods[0].times) > 8
    worst = -np.inf
    for t in np.linspace(0.0, 1.0, 101):
        shape = stacking.surface.at(float(t))
        assert shape is not None
        floor, _ = heights_below(shape.vertices, [ridge])
        worst = max(worst, float((floor - shape.vertices[:, 2]).max()))
    assert worst <= 0.02  # not 100 m through the ridge
    unrefined = keep_above(younger, [ridge], max_halvings=0)
    assert unrefined.residual > 50.0 and len(unrefined.surface.periods[0].times) == 2
    with pytest.raises(InvalidInputError, match="between instants"):
        keep_above(younger, [ridge], between=-1.0)


def test_keep_above_carries_the_properties_through_the_instants_it_adds() -> None:
    base = grid(4)
    low, high = base.vertices.copy(), base.vertices.copy()
    low[:, 2], high[:, 2] = 1.0, 1.0
    older = _evolving([0.0, 1.0, 2.0], [low - [0, 0, 5], low + [0, 0, 5], low - [0, 0, 5]], base, "older")
    younger = EvolvingSurface(
        [
            TopologyPeriod(
                [0.0, 2.0],
                base.cells,
                np.stack([low, high]),
                vertex_properties={"porosity": np.stack([np.full(16, 0.1), np.full(16, 0.3)])},
                properties={"age": [10, 12]},
            )
        ]
    )
    stacking = keep_above(younger, [older])
    period = stacking.surface.periods[0]
    assert period.times.tolist() == [0.0, 1.0, 2.0]
    np.testing.assert_allclose(period.vertex_properties["porosity"][1], 0.2)
    np.testing.assert_allclose(period.properties["age"].astype(np.float64), [10.0, 11.0, 12.0])
    np.testing.assert_allclose(period.positions[1][:, 2], 6.0)  # raised onto the older surface at t = 1
