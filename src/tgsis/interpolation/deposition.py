"""Deposition: a unit that grows from the surface beneath it, and younger tops kept above older ones.

The source design interpolates a unit deposited during [t1, t2] from *its
own top at t2* (the source) to *the older surface at t1* (the target): the
unit starts as the surface it lies on, with the vertex correspondence the
interpolation finds, and thickens into its top. :func:`deposit` does that
with :func:`~tgsis.interpolation.interpolate.interpolate` and puts the first
shape exactly on the surface beneath; :func:`drape` makes that surface on
the top's own triangulation when the unit lies on several older surfaces
(partly on the basement, partly on an older unit) or on one much larger
than itself.

Interpolated separately, two units can still cross between their known
instants (each vertex follows its own trajectory). :func:`keep_above`
enforces the stratigraphic rule that a younger top never passes below an
older one: wherever a vertex of the younger surface would lie below the
highest older surface straight beneath it, it is put on that surface, and
the vertices so placed, with how far they were raised and which surface
they lie on, are returned as the erosion/onlap :class:`Contact`.

Heights are taken vertically (along z), so the older surfaces must be
single-valued over (x, y) where they are compared (horizons, tops, a
basement); a steep fault is not one of them. Pure numpy; no database.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.interpolation.interpolate import Interpolation, interpolate
from tgsis.interpolation.parameterize import PointLocator
from tgsis.interpolation.setup import InterpolationSetup
from tgsis.mesh import Surface
from tgsis.temporal import EvolvingSurface, TopologyPeriod

__all__ = ["Contact", "Deposition", "Stacking", "deposit", "drape", "heights_below", "keep_above"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]
BoolArray = npt.NDArray[np.bool_]


# --------------------------------------------------------------------------- heights under points


def _xy(points: npt.ArrayLike) -> FloatArray:
    array = np.asarray(points, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] not in (2, 3):
        raise InvalidInputError(f"points must have shape (p, 2) or (p, 3), got {array.shape}")
    if not np.all(np.isfinite(array[:, :2])):
        raise InvalidInputError("points must have finite x and y")
    return np.ascontiguousarray(array[:, :2])


class _HeightField:
    """A surface's height over (x, y): its triangles located once, then any number of points."""

    def __init__(self, vertices: FloatArray, cells: IntArray) -> None:
        # the projection of a steep triangle is a sliver: leave it out rather than divide by its area
        corners = vertices[cells][:, :, :2]
        e1, e2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
        area = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        extent = float(np.ptp(vertices[:, :2], axis=0).max()) if len(vertices) else 0.0
        self.z = vertices[:, 2]
        self.triangles = cells[area > 1e-12 * max(extent, 1.0) ** 2]
        self.locator = PointLocator(vertices[:, :2], self.triangles) if len(self.triangles) else None

    @classmethod
    def of(cls, surface: Surface) -> _HeightField:
        return cls(surface.vertices, surface.cells)

    @classmethod
    def at(cls, evolving: EvolvingSurface, t: float) -> _HeightField | None:
        """The evolving surface's height field at ``t`` (None when it does not exist then), as ``at(t)`` shapes it."""
        frame = evolving.frame(t)
        if frame is None:
            return None
        period = evolving.periods[frame.period]
        a = period.positions[frame.j0]
        xyz = a if frame.j0 == frame.j1 else a + frame.w * (period.positions[frame.j1] - a)
        return cls(xyz, period.triangles)

    def heights(self, xy: FloatArray) -> FloatArray:
        """(p,) height straight above or below each point, NaN where the surface's projection does not reach."""
        heights = np.full(len(xy), np.nan)
        if self.locator is None or len(xy) == 0:
            return heights
        triangle, bary, _ = self.locator.locate(xy)
        found = triangle >= 0
        heights[found] = (bary[found] * self.z[self.triangles[triangle[found]]]).sum(axis=1)
        return heights


def _highest(xy: FloatArray, fields: Sequence[_HeightField | None]) -> tuple[FloatArray, IntArray]:
    best = np.full(len(xy), -np.inf)
    which = np.full(len(xy), -1, dtype=np.int64)
    for index, field in enumerate(fields):
        if field is None:
            continue
        z = field.heights(xy)
        higher = np.isfinite(z) & (z > best)
        best[higher] = z[higher]
        which[higher] = index
    return np.where(which >= 0, best, np.nan), which


def heights_below(points: npt.ArrayLike, surfaces: Sequence[Surface | None]) -> tuple[FloatArray, IntArray]:
    """The highest of ``surfaces`` straight above or below each point, and which one it is.

    Parameters
    ----------
    points : (p, 2) or (p, 3) array_like of float
        Only x and y are used.
    surfaces : sequence of Surface or None
        Single-valued over (x, y) where they reach the points (horizons,
        unit tops); ``None`` entries (a surface that does not exist at some
        time) are skipped but keep their index.

    Returns
    -------
    z : (p,) ndarray of float64
        Height of the highest surface at each point's (x, y); NaN where none reaches.
    which : (p,) ndarray of int64
        Index in ``surfaces`` of that surface; -1 where none reaches.
    """
    return _highest(_xy(points), [None if s is None else _HeightField.of(s) for s in surfaces])


def drape(top: Surface, older: Sequence[Surface], *, name: str | None = None) -> Surface:
    """The older surface under ``top``, on ``top``'s triangulation: each vertex moved straight down (or up) onto it.

    Use it as the target of :func:`deposit` when the unit lies on several
    older surfaces (the highest one under each vertex counts) or on one that
    reaches far beyond it; the set-up's target controls are then the same
    vertex indices as the source's.

    Parameters
    ----------
    top : Surface
        The unit's top; its (x, y) and triangles are kept.
    older : sequence of Surface
        The older surfaces at the deposition's start.
    name : str, optional
        Default: ``top``'s name.

    Returns
    -------
    Surface
        (n, 3) vertices on the highest older surface, ``top``'s triangles.

    Raises
    ------
    InvalidGeometryError
        A vertex of ``top`` with no older surface straight beneath it (counted, the first named).
    """
    if not older:
        raise InvalidInputError("drape needs at least one older surface to lie on")
    z, which = heights_below(top.vertices, older)
    lost = np.flatnonzero(which < 0)
    if len(lost):
        raise InvalidGeometryError(
            f"{len(lost)} of {top.n_vertices} vertices of {top.name or 'the top'} have no older surface "
            f"straight beneath them (the first: vertex {int(lost[0])} at x={top.vertices[lost[0], 0]:g}, "
            f"y={top.vertices[lost[0], 1]:g})",
            hint="give the older surfaces that cover the unit's whole extent (the basement, say)",
        )
    vertices = top.vertices.copy()
    vertices[:, 2] = z
    return Surface(vertices, top.cells, name=name if name is not None else top.name)


# --------------------------------------------------------------------------- deposition


@dataclass(frozen=True)
class Deposition:
    """A unit deposited during [start, end]: it starts on the surface beneath and grows into its top.

    Attributes
    ----------
    evolving : EvolvingSurface
        One topology period from ``start`` (on the surface beneath) to ``end`` (the unit's top).
    interpolation : Interpolation
        The interpolation from the top (source, at ``end``) to the surface beneath (target, at ``start``).
    start, end : float
    settled : float
        How far the first shape was moved vertically to lie exactly on the
        surface(s) beneath (0 up to rounding when the target is that surface
        itself; the chord error when it was draped).
    """

    evolving: EvolvingSurface
    interpolation: Interpolation
    start: float
    end: float
    settled: float


def deposit(
    top: Surface,
    beneath: Surface | Sequence[Surface],
    setup: InterpolationSetup,
    start: float,
    end: float,
    *,
    name: str | None = None,
    surfaces: Mapping[str, Surface] | None = None,
    alive: bool = False,
) -> Deposition:
    """A unit deposited during [``start``, ``end``]: at ``start`` it is the surface beneath, at ``end`` its top.

    As the source design does it: the interpolation runs from the unit's top
    at ``end`` (the source) to the older surface at ``start`` (the target),
    so each vertex of the top finds where it starts on the surface beneath
    (the compatible target) and the unit thickens along the trajectories.
    The first shape is then put exactly on the surface beneath (vertically,
    onto the highest of the surfaces given).

    Parameters
    ----------
    top : Surface
        The unit's top at ``end``: the interpolation's source.
    beneath : Surface or sequence of Surface
        The older surface the unit lies on at ``start``, the target (the
        set-up's target controls index its vertices); or the older surfaces
        at ``start`` (several, or one that reaches beyond the unit): the
        target is then :func:`drape` of ``top`` on them, and the set-up's
        target controls must equal its source controls.
    setup : InterpolationSetup
        Control pairs, fences, attachments, m, ε, as for :func:`interpolate`.
    start, end : float
        ``start < end``, finite.
    name : str, optional
        Default: ``top``'s name.
    surfaces : mapping of str to Surface, optional
        The controlling surfaces by name (see :func:`interpolate`).
    alive : bool
        Whether the evolving surface exists after ``end``.

    Returns
    -------
    Deposition

    Raises
    ------
    InvalidInputError
        ``start`` not before ``end``; draped target with different source and target controls.
    InvalidGeometryError
        A vertex of ``top`` with no older surface beneath it (draped target).
    InterpolationSetupError, ParameterizationError, TrajectoryError, ProjectionError
        As :func:`interpolate`.
    """
    if not (np.isfinite(start) and np.isfinite(end) and start < end):
        raise InvalidInputError(
            f"a deposition runs from its start to a later end, got start={start}, end={end}",
            hint="start is when the unit begins on the surface beneath, end the time of its top",
        )
    older = [beneath] if isinstance(beneath, Surface) else list(beneath)
    if not older or not all(isinstance(s, Surface) for s in older):
        raise InvalidInputError("beneath must be a Surface or a non-empty sequence of Surface")
    if isinstance(beneath, Surface):
        target = beneath
    else:
        if tuple(setup.target_controls) != tuple(setup.source_controls):
            raise InvalidInputError(
                "the target is draped on the top's own triangulation, so the target controls must be the source "
                f"controls: got {list(setup.source_controls)} and {list(setup.target_controls)}"
            )
        target = drape(top, older)
    result = interpolate(
        top, target, setup, end, start, name=name if name is not None else top.name, surfaces=surfaces, alive=alive
    )
    period = result.evolving.periods[0]
    positions = period.positions.copy()  # (m, n, 3), forward in time: [0] at start
    floor, which = heights_below(positions[0], older)
    on = which >= 0
    settled = float(np.abs(floor[on] - positions[0, on, 2]).max(initial=0.0))
    positions[0, on, 2] = floor[on]
    evolving = EvolvingSurface(
        [
            TopologyPeriod(
                period.times,
                period.triangles,
                positions,
                vertex_properties=dict(period.vertex_properties),
                cell_properties=dict(period.cell_properties),
                properties=dict(period.properties),
            )
        ],
        alive=alive,
        name=result.evolving.name,
        color=result.evolving.color,
    )
    return Deposition(evolving, result, float(start), float(end), settled)


# --------------------------------------------------------------------------- younger above older


@dataclass(frozen=True)
class Contact:
    """Where a younger surface lies on older ones during one of its topology periods.

    Attributes
    ----------
    period : int
        Index of the topology period of the younger surface.
    times : (g,) ndarray of float64
        The period's geometry instants (after :func:`keep_above` added the older surfaces' instants).
    lies_on : (g, n) ndarray of int64
        Per instant and vertex: index (in the older surfaces given) of the
        surface the vertex lies on, within the tolerance; -1 where it lies
        above every older surface (or none is beneath it).
    raised : (g, n) ndarray of float64
        How far the vertex was below that surface and was raised onto it (0 where it was not below).
    """

    period: int
    times: FloatArray
    lies_on: IntArray
    raised: FloatArray

    @property
    def clamped(self) -> BoolArray:
        """(g, n) bool: the vertices that were below an older surface and were put on it."""
        return np.asarray(self.raised > 0.0)

    @property
    def max_raise(self) -> float:
        """The most any vertex was raised, in the model's length unit."""
        return float(self.raised.max(initial=0.0))


@dataclass(frozen=True)
class Stacking:
    """A younger surface kept above older ones (:func:`keep_above`), and its contacts with them.

    Attributes
    ----------
    surface : EvolvingSurface
        The younger surface, never below an older one at any of its geometry instants.
    contacts : tuple of Contact
        One per topology period of ``surface``.
    residual : float
        The most a vertex of ``surface`` lies below an older surface at a
        quarter, half or three quarters of the way between two consecutive
        geometry instants (≤ 0: never; at most the ``between`` asked for
        unless the refinement stopped at its limit).
    """

    surface: EvolvingSurface
    contacts: tuple[Contact, ...]
    residual: float

    @property
    def max_raise(self) -> float:
        """The most any vertex was raised at any instant."""
        return max((c.max_raise for c in self.contacts), default=0.0)

    @property
    def clamped(self) -> int:
        """How many (vertex, instant) pairs were raised."""
        return int(sum(int(c.clamped.sum()) for c in self.contacts))

    def lies_on(self) -> list[int]:
        """Indices of the older surfaces the younger one lies on at some instant, ascending."""
        found: set[int] = set()
        for contact in self.contacts:
            found.update(int(i) for i in np.unique(contact.lies_on) if i >= 0)
        return sorted(found)


def _older_times(older: Sequence[EvolvingSurface | Surface]) -> FloatArray:
    times = [s.geometry_instants for s in older if isinstance(s, EvolvingSurface)]
    return np.unique(np.concatenate(times)) if times else np.zeros(0)


class _Samples:
    """A topology period's geometry instants as growable float arrays: times, positions, per-instant values."""

    def __init__(self, period: TopologyPeriod) -> None:
        self.times = period.times.copy()
        self.positions = period.positions.copy()
        self.series = {("vertex", k): np.asarray(v, dtype=np.float64) for k, v in period.vertex_properties.items()}
        self.series.update({("cell", k): np.asarray(v, dtype=np.float64) for k, v in period.cell_properties.items()})
        self.series.update({("feature", k): np.asarray(v, dtype=np.float64) for k, v in period.properties.items()})

    def insert(self, times: FloatArray) -> FloatArray:
        """Add instants strictly inside the period, linear between the two around each; return those added."""
        new = np.setdiff1d(times[(times > self.times[0]) & (times < self.times[-1])], self.times)
        if len(new) == 0:
            return new
        j1 = np.searchsorted(self.times, new)
        j0 = j1 - 1
        w = (new - self.times[j0]) / (self.times[j1] - self.times[j0])

        def mix(values: FloatArray) -> FloatArray:
            shape = (len(new),) + (1,) * (values.ndim - 1)
            return np.asarray(values[j0] + w.reshape(shape) * (values[j1] - values[j0]), dtype=np.float64)

        order = np.argsort(np.concatenate([self.times, new]), kind="stable")
        self.times = np.concatenate([self.times, new])[order]
        self.positions = np.concatenate([self.positions, mix(self.positions)])[order]
        self.series = {k: np.concatenate([v, mix(v)])[order] for k, v in self.series.items()}
        return new

    def period(self, triangles: IntArray) -> TopologyPeriod:
        def kind(name: str) -> dict[str, FloatArray]:
            return {k: v for (what, k), v in self.series.items() if what == name}

        return TopologyPeriod(
            self.times,
            triangles,
            self.positions,
            vertex_properties=kind("vertex"),
            cell_properties=kind("cell"),
            properties=kind("feature"),
        )


class _Floors:
    """The older surfaces' height fields at any time: a constant surface's built once, an evolving one's per time."""

    def __init__(self, older: Sequence[EvolvingSurface | Surface]) -> None:
        self.older = list(older)
        self.constant = {i: _HeightField.of(s) for i, s in enumerate(self.older) if isinstance(s, Surface)}
        self.cache: dict[float, list[_HeightField | None]] = {}

    def _fields(self, t: float) -> list[_HeightField | None]:
        fields = self.cache.get(t)
        if fields is None:
            fields = []
            for i, s in enumerate(self.older):
                fields.append(self.constant[i] if isinstance(s, Surface) else _HeightField.at(s, t))
            if len(self.cache) > 512:
                self.cache.clear()
            self.cache[t] = fields
        return fields

    def at(self, points: FloatArray, t: float) -> tuple[FloatArray, IntArray]:
        """(n,) height of the highest older surface under each point at ``t``, and its index (-1: none)."""
        return _highest(np.ascontiguousarray(points[:, :2]), self._fields(t))

    def highest_dip(self, shapes: FloatArray, times: FloatArray) -> FloatArray:
        """(k,) how far the lowest vertex of each of the k shapes (k, n, 3) at ``times`` lies below the older surfaces.

        The constant older surfaces take all the points at once; each evolving one is taken at each time.
        """
        k, n = shapes.shape[:2]
        best = np.full((k, n), -np.inf)
        flat = np.ascontiguousarray(shapes[..., :2].reshape(-1, 2))
        for field in self.constant.values():
            z = field.heights(flat).reshape(k, n)
            best = np.where(np.isfinite(z) & (z > best), z, best)
        for j, t in enumerate(times):
            for i, moving in enumerate(self._fields(float(t))):
                if moving is not None and i not in self.constant:
                    z = moving.heights(np.ascontiguousarray(shapes[j, :, :2]))
                    best[j] = np.where(np.isfinite(z) & (z > best[j]), z, best[j])
        reached = np.isfinite(best)
        dips: FloatArray = np.where(reached, best - shapes[..., 2], -np.inf).max(axis=1, initial=-np.inf)
        return dips


def keep_above(
    younger: EvolvingSurface,
    older: Sequence[EvolvingSurface | Surface],
    *,
    tolerance: float = 1e-6,
    between: float | None = None,
    max_halvings: int = 10,
) -> Stacking:
    """Keep a younger surface from passing below older ones: put it on them where it would, and say where.

    At every geometry instant of the younger surface, each vertex that lies
    below the highest older surface straight beneath it is raised onto that
    surface. The geometry instants of the older surfaces inside each of the
    younger's periods are added to it first (its shapes do not change: they
    are linear in time between instants), so the rule holds exactly at
    every instant where either surface has a shape. Between instants the
    vertices move on straight lines while the older surface under them
    curves, so a vertex can dip below it there; wherever it would by more
    than ``between`` a quarter, half or three quarters of the way between
    two instants, the halfway instant is added (and raised), and so on, at
    most ``max_halvings`` times. (Sampled, so not a proof: a dip narrower
    than a quarter of the finest interval can remain; ``residual`` says what
    the samples found.)

    Parameters
    ----------
    younger : EvolvingSurface
        A unit's top through time.
    older : sequence of EvolvingSurface or Surface
        The older tops (and the basement) at the same times; a ``Surface``
        is the same at every time; an evolving surface counts only while it
        exists. Single-valued over (x, y).
    tolerance : float
        A vertex this close to an older surface (after raising) lies on it:
        part of the contact.
    between : float, optional
        Largest dip allowed between two instants (at the samples); default 1e-6
        times the younger surface's largest horizontal extent.
    max_halvings : int
        How many times an interval between instants may be halved.

    Returns
    -------
    Stacking
        The younger surface raised where it had to be, one :class:`Contact`
        per topology period (the erosion/onlap contact), and the residual
        dip between instants. Consecutive periods that shared their shape at
        their common instant still do (the same rule applied to the same shape).

    Raises
    ------
    InvalidInputError
        A negative or non-finite tolerance or ``between``, a negative ``max_halvings``.
    """
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise InvalidInputError(f"the contact tolerance must be a finite length >= 0, got {tolerance!r}")
    if between is None:
        extent = max(float(np.ptp(p.positions[..., :2].reshape(-1, 2), axis=0).max()) for p in younger.periods)
        between = 1e-6 * max(extent, 1.0)
    if not (np.isfinite(between) and between >= 0):
        raise InvalidInputError(f"the dip allowed between instants must be a finite length >= 0, got {between!r}")
    if not (isinstance(max_halvings, int) and max_halvings >= 0):
        raise InvalidInputError(f"max_halvings must be an integer >= 0, got {max_halvings!r}")
    extra = _older_times(older)
    floors = _Floors(older)
    periods: list[TopologyPeriod] = []
    contacts: list[Contact] = []
    residual = -np.inf
    for index, period in enumerate(younger.periods):
        samples = _Samples(period)
        samples.insert(extra)
        raised_at: dict[float, FloatArray] = {}

        def raise_instants(
            times: FloatArray, samples: _Samples = samples, raised_at: dict[float, FloatArray] = raised_at
        ) -> None:
            for t in times:
                j = int(np.searchsorted(samples.times, t))
                floor, which = floors.at(samples.positions[j], float(t))
                below = np.zeros(len(floor), dtype=bool)
                below[which >= 0] = samples.positions[j, which >= 0, 2] < floor[which >= 0]
                lift = np.zeros(len(floor))
                lift[below] = floor[below] - samples.positions[j, below, 2]
                samples.positions[j, below, 2] = floor[below]
                raised_at[float(t)] = lift

        raise_instants(samples.times)
        # the dip at a quarter, half and three quarters of each interval (a steep older surface, a pinch-out,
        # can hide one near an end from the middle alone); only the halves of an interval just split are
        # looked at again: the others did not change
        dips: dict[float, float] = {}
        check = samples.times[:-1]
        for halving in range(max_halvings + 1):
            rows = np.flatnonzero(np.isin(samples.times[:-1], check))
            t0, t1 = samples.times[rows], samples.times[rows + 1]
            p0, p1 = samples.positions[rows], samples.positions[rows + 1]
            found = np.full(len(rows), -np.inf)
            for w in (0.25, 0.5, 0.75):
                found = np.maximum(found, floors.highest_dip(p0 + w * (p1 - p0), t0 + w * (t1 - t0)))
            dips.update(zip(t0.tolist(), found.tolist()))
            bad = found > between
            if not bad.any() or halving == max_halvings:
                break
            added = samples.insert((t0[bad] + t1[bad]) / 2)
            raise_instants(added)
            check = np.concatenate([t0[bad], added])
        residual = max(residual, max(dips.values(), default=-np.inf))
        g, n = samples.positions.shape[:2]
        lies_on = np.full((g, n), -1, dtype=np.int64)
        raised = np.stack([raised_at[float(t)] for t in samples.times])
        for j, t in enumerate(samples.times):
            floor, which = floors.at(samples.positions[j], float(t))
            touching = (which >= 0) & (samples.positions[j, :, 2] - np.where(which >= 0, floor, 0.0) <= tolerance)
            lies_on[j, touching] = which[touching]
        periods.append(samples.period(period.triangles))
        contacts.append(Contact(index, samples.times.copy(), lies_on, raised))
    surface = EvolvingSurface(periods, alive=younger.alive, name=younger.name, color=younger.color)
    return Stacking(surface, tuple(contacts), float(residual))
