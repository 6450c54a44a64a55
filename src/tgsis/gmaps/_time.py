"""G-maps evolving in valid time (model 4): topology periods of fixed darts with moving points.

A model-4 object is a sequence of topology periods (``../shared/spec/data-models.md``):
within a period the darts and involutions stay, the points of the embedding
are known at geometry instants and move linearly in between; at a topology
instant the next period's G-map takes over (the old period's last shape and
the new one's first share their time). Properties of the i-cells of one
level are known at the same instants and are linear in between too. The
shape at t follows the rules of model 3 (:func:`tgsis.temporal.frame_at`):
nothing before the first instant, the last state after the end if alive.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import numpy.typing as npt

from tgsis._series import Frame, as_series, as_times, frame_at
from tgsis._transition import closest_on_segments, prepend_first, start_on, transition_times
from tgsis.errors import InvalidGMapError, InvalidInputError, InvalidPropertyError
from tgsis.gmaps._core import GMap

FloatArray = npt.NDArray[np.float64]


class GMapPeriod:
    """One topology period of an :class:`EvolvingGMap`: fixed darts and involutions, moving points.

    Parameters
    ----------
    times : (g,) array_like of float
        Geometry instants, strictly increasing; ``times[0]`` starts the period.
    gmap : GMap
        The period's topology and embedding; its points are the positions at
        ``times[0]`` unless ``positions`` is given.
    positions : (g, k, m) array_like of float, optional
        The k points (``gmap.points``) at each geometry instant. Default:
        the points of ``gmap``, constant over the period.
    level : int, optional
        The cell level that ``cell_values`` belong to (0..n).
    cell_values : mapping of str to (g, c) array_like, optional
        Numeric values of the c ``level``-cells (:meth:`GMap.cells` order) at
        each geometry instant.

    Raises
    ------
    InvalidInputError, InvalidGMapError, InvalidPropertyError
    """

    def __init__(
        self,
        times: npt.ArrayLike,
        gmap: GMap,
        positions: npt.ArrayLike | None = None,
        *,
        level: int | None = None,
        cell_values: Mapping[str, npt.ArrayLike] | None = None,
    ) -> None:
        if not isinstance(gmap, GMap):
            raise InvalidInputError(f"a G-map period needs a tgsis.gmaps.GMap, got {type(gmap).__name__}")
        self.times = as_times(times, "geometry instants of a G-map period")
        g, (k, m) = len(self.times), gmap.points.shape
        if positions is None:
            xyz = np.broadcast_to(gmap.points, (g, k, m)).copy()
        else:
            xyz = np.ascontiguousarray(positions, dtype=np.float64)
        if xyz.shape != (g, k, m):
            raise InvalidGMapError(
                f"point positions of a G-map period must have shape (g, k, m) = ({g}, {k}, {m}), got {xyz.shape}"
            )
        if not np.all(np.isfinite(xyz)):
            raise InvalidGMapError("point positions must be finite (NaN or infinite coordinate found)")
        if level is None and cell_values:
            raise InvalidPropertyError("cell values need the level of the cells they belong to (level=...)")
        if level is not None and not 0 <= level <= gmap.dimension:
            raise InvalidPropertyError(f"cell level {level} is not a cell dimension of a {gmap.dimension}-G-map")
        self.gmap = GMap(gmap.alpha, gmap.vertex, xyz[0])
        self.positions = xyz
        self.positions.flags.writeable = False
        self.level = level
        count = gmap.n_cells(level) if level is not None else 0
        self.cell_values = as_series(cell_values, (g, count), f"property of {level}-cells")

    @property
    def start(self) -> float:
        """Where the period starts (its topology instant)."""
        return float(self.times[0])

    def shape_at(self, j0: int, j1: int, w: float) -> GMap:
        """The G-map between geometry instants ``j0 <= j1`` at weight ``w`` of the later one.

        Points and cell values (as float64) are ``a + w * (b - a)``, the
        formula the SQL snapshot (``tgsis.gmap_points_at``) uses.
        """

        def mix(a: npt.NDArray[np.generic], b: npt.NDArray[np.generic]) -> FloatArray:
            a64, b64 = a.astype(np.float64), b.astype(np.float64)
            return a64 if j0 == j1 else a64 + w * (b64 - a64)

        values = {name: mix(v[j0], v[j1]) for name, v in self.cell_values.items()}
        return GMap(
            self.gmap.alpha,
            self.gmap.vertex,
            mix(self.positions[j0], self.positions[j1]),
            cell_properties={self.level: values} if self.level is not None and values else None,
        )


def sudden_gmap_change(before: GMap, period: GMapPeriod, duration: float, *, label: str = "the period") -> GMapPeriod:
    """``period`` starting in the shape ``before`` and reaching its own first shape ``duration`` later, linearly.

    The design's sudden change (see :func:`tgsis.temporal.sudden_change`)
    for a G-map: the post-object's points start at the pre-object's points
    with the same index when both G-maps have as many points and the same
    involutions and vertex map (a motion); otherwise each at the closest
    point of ``before``'s edges once the new shape's offset as a whole is
    taken out (the edges are what the continuity check measures against). Cell values keep their first values over the
    transition.

    Raises
    ------
    InvalidInputError
        A bad duration, one that does not end before the second instant, or
        a G-map of another embedding dimension.
    """
    if before.embedding_dimension != period.gmap.embedding_dimension:
        raise InvalidInputError(
            f"{label} is in R^{period.gmap.embedding_dimension}, the shape before it in R^{before.embedding_dimension}"
        )
    times = transition_times(period.times, duration, label)
    same = (
        len(before.points) == len(period.gmap.points)
        and len(before.alpha) == len(period.gmap.alpha)
        and all(np.array_equal(a, b) for a, b in zip(before.alpha, period.gmap.alpha))
        and np.array_equal(before.vertex, period.gmap.vertex)
    )
    points = before.points.astype(np.float64)
    edges = (
        np.stack([before.vertex, before.vertex[before.alpha[0]]], axis=1)
        if before.n_darts
        else np.empty((0, 2), dtype=np.int64)
    )
    start = points if same else start_on(lambda q: closest_on_segments(points, edges, q), period.positions[0])
    return GMapPeriod(
        times,
        period.gmap,
        prepend_first(period.positions, start),
        level=period.level,
        cell_values={k: prepend_first(v) for k, v in period.cell_values.items()},
    )


class EvolvingGMap:
    """An n-G-map evolving in valid time, with topology changes at period starts (model 4).

    Parameters
    ----------
    periods : sequence of GMapPeriod
        In time order; each but the last ends where the next starts (its last
        geometry instant is the next one's first). All of one dimension and
        one embedding dimension, and of one cell level when they have values.
    alive : bool
        Whether the object exists after its last geometry instant.
    name : str, optional

    Raises
    ------
    InvalidInputError
        No period, periods that do not follow each other, or of different
        dimensions.
    """

    def __init__(self, periods: Sequence[GMapPeriod], *, alive: bool = False, name: str | None = None) -> None:
        self.periods = tuple(periods)
        if not self.periods or not all(isinstance(p, GMapPeriod) for p in self.periods):
            raise InvalidInputError("an evolving G-map needs at least one GMapPeriod")
        first = self.periods[0]
        for i, (a, b) in enumerate(zip(self.periods, self.periods[1:])):
            if a.times[-1] != b.times[0]:
                raise InvalidInputError(
                    f"G-map period {i} must end where period {i + 1} starts: its last geometry instant is "
                    f"{float(a.times[-1])!r}, period {i + 1} starts at {float(b.times[0])!r}",
                    hint="a sudden change is a change over a very short period",
                )
        for i, p in enumerate(self.periods):
            if (p.gmap.dimension, p.gmap.embedding_dimension) != (first.gmap.dimension, first.gmap.embedding_dimension):
                raise InvalidInputError(
                    f"G-map period {i} is a {p.gmap.dimension}-G-map in "
                    f"R^{p.gmap.embedding_dimension}, period 0 a {first.gmap.dimension}-G-map "
                    f"in R^{first.gmap.embedding_dimension}"
                )
        levels = {p.level for p in self.periods if p.cell_values and p.level is not None}
        if len(levels) > 1:
            raise InvalidPropertyError(f"the periods' cell values belong to different levels {sorted(levels)}")
        self.alive = bool(alive)
        self.name = name
        self._starts = np.array([p.start for p in self.periods])

    @classmethod
    def constant(
        cls,
        gmap: GMap,
        start: float,
        end: float,
        *,
        alive: bool = False,
        level: int | None = None,
        name: str | None = None,
    ) -> EvolvingGMap:
        """A G-map that stays as it is from ``start`` to ``end`` (one period, two geometry instants).

        The cell properties of ``level`` (default: the only level ``gmap``
        has properties on, if any) are carried, constant too.
        """
        levels = sorted(gmap.cell_properties)
        if level is None and len(levels) > 1:
            raise InvalidPropertyError(f"the G-map has properties on levels {levels}: say which one (level=...)")
        chosen = level if level is not None else (levels[0] if levels else None)
        values = (
            {k: np.stack([v, v]) for k, v in gmap.cell_properties.get(chosen, {}).items()} if chosen is not None else {}
        )
        return cls([GMapPeriod([start, end], gmap, level=chosen, cell_values=values)], alive=alive, name=name)

    def with_sudden_changes(self, duration: float) -> EvolvingGMap:
        """The same G-map with every topology change made a short linear transition (:func:`sudden_gmap_change`).

        ``tgsis.insert_feature(..., sudden_change=duration)`` stores this.
        """
        periods = [self.periods[0]]
        for i, period in enumerate(self.periods[1:], start=1):
            previous = self.periods[i - 1]
            last = len(previous.times) - 1
            periods.append(
                sudden_gmap_change(previous.shape_at(last, last, 0.0), period, duration, label=f"G-map period {i}")
            )
        return EvolvingGMap(periods, alive=self.alive, name=self.name)

    @property
    def dimension(self) -> int:
        """n of the n-G-map."""
        return self.periods[0].gmap.dimension

    @property
    def embedding_dimension(self) -> int:
        """m: the points are in R^m."""
        return self.periods[0].gmap.embedding_dimension

    @property
    def level(self) -> int | None:
        """The cell level of the periods' values (None: no values)."""
        return next((p.level for p in self.periods if p.cell_values), None)

    @property
    def start(self) -> float:
        """The first topology instant."""
        return float(self._starts[0])

    @property
    def end(self) -> float:
        """The last geometry instant (the object lasts for ever after it if alive)."""
        return float(self.periods[-1].times[-1])

    @property
    def n_darts(self) -> int:
        """Darts over all periods."""
        return sum(p.gmap.n_darts for p in self.periods)

    def frame(self, t: float) -> Frame | None:
        """The period and bracketing geometry instants at ``t``, or None when the object does not exist then."""
        return frame_at(self._starts, [p.times for p in self.periods], self.alive, t)

    def at(self, t: float) -> GMap | None:
        """The G-map at ``t`` (points and cell values interpolated), or None when the object does not exist then."""
        frame = self.frame(t)
        if frame is None:
            return None
        return self.periods[frame.period].shape_at(frame.j0, frame.j1, frame.w)

    def check(self, *, raise_: bool = False) -> list[str]:
        """The problems of every period's G-map (conditions (i)-(iii), shared points), named by period.

        Each period's darts are closed under the involutions by construction
        (each period is a G-map of its own); the database check
        (``tgsis.gmap_check``) verifies the closure of stored rows.

        Raises
        ------
        InvalidGMapError
            With ``raise_=True``, when a period is not a valid G-map.
        """
        problems = [
            f"period {i} (from t = {p.start!r}): {problem}"
            for i, p in enumerate(self.periods)
            for problem in p.gmap.check().problems()
        ]
        if raise_ and problems:
            raise InvalidGMapError(
                f"not a valid evolving {self.dimension}-G-map: {problems[0]}",
                detail="; ".join(problems[1:]) or None,
                hint="EvolvingGMap.check() lists every problem",
            )
        return problems

    def __repr__(self) -> str:
        return (
            f"EvolvingGMap({len(self.periods)} periods {self.start!r}..{self.end!r}, {self.dimension}-G-map in "
            f"R^{self.embedding_dimension}, {self.n_darts} darts, alive={self.alive}, name={self.name!r})"
        )
