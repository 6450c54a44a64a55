"""Surfaces in time on numpy arrays: known at instants (model 2) and evolving continuously (model 3).

No database here; :mod:`tgsis.db.temporal` stores and queries these objects.
Model time is a float where larger is later (the feature class records its
unit).

* :class:`SurfaceSeries` (model 2): a surface known at instants
  t0 < t1 < ... < tk and constant in between. Its shape at t is a step
  function with either convention:

  - ``"left"`` (left-closed): G(t) = G_i for t_i <= t < t_i+1, and G_k at t_k;
  - ``"right"`` (right-closed): G(t) = G_0 at t_0, G_i for t_i-1 < t <= t_i.

* :class:`EvolvingSurface` (model 3): a list of :class:`TopologyPeriod`. Each
  period keeps one triangle list while its nodes move along straight lines
  between the period's geometry instants; the topology changes only where a
  period starts. The shape at t: take the last period starting at or before
  t; inside it the bracketing geometry instants t_j <= t <= t_j+1 and every
  node at x(t) = x_j + w (x_j+1 - x_j), w = (t - t_j) / (t_j+1 - t_j). At the
  start of a period the new topology applies.

For both: nothing exists before the first instant, and after the last one
the last shape holds if the object is ``alive``, else nothing exists.
:meth:`SurfaceSeries.at` and :meth:`EvolvingSurface.at` compute exactly what
the SQL functions ``tgsis.vertices_at`` / ``tgsis.triangles_at`` return (the
same float operations in the same order).

Time series for ParaView: :func:`series_frames` samples either object at
given times (by default at its own instants, :func:`own_instants`;
:func:`even_times` spaces them evenly), and :func:`write_series_pvd` writes
the samples as a ``.pvd`` collection of ``.vtu`` frames
(:func:`tgsis.formats.pvd.write_pvd`; a time where the object does not exist
becomes an empty grid). :func:`tgsis.db.temporal.export_series` does the same
from the database.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, TypeAlias

import numpy as np
import numpy.typing as npt

from tgsis._series import Frame, as_series, as_times, check_time, frame_at
from tgsis._transition import closest_on_triangles, prepend_first, start_on, transition_times
from tgsis.errors import InvalidGeometryError, InvalidInputError
from tgsis.formats._common import PathLike
from tgsis.formats.pvd import write_pvd
from tgsis.formats.vtk import Encoding
from tgsis.mesh import Surface

__all__ = [
    "Convention",
    "SurfaceSeries",
    "TopologyPeriod",
    "EvolvingSurface",
    "Color",
    "TemporalSurface",
    "SurfaceFrame",
    "WrittenSeries",
    "own_instants",
    "even_times",
    "series_frames",
    "write_frames_pvd",
    "write_series_pvd",
    "Period",
    "sudden_change",
]

#: Step convention of model 2 queries.
Convention = Literal["left", "right"]
#: Display colour (red, green, blue), each in [0, 1].
Color = tuple[float, float, float]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


def check_convention(convention: str) -> Convention:
    """``"left"`` or ``"right"``; :class:`~tgsis.errors.InvalidInputError` otherwise."""
    if convention == "left":
        return "left"
    if convention == "right":
        return "right"
    raise InvalidInputError(f"step convention {convention!r} must be 'left' or 'right'")


def _as_color(color: Sequence[float] | None) -> Color | None:
    if color is None:
        return None
    values = tuple(float(c) for c in color)
    if len(values) != 3 or not all(0.0 <= c <= 1.0 for c in values):
        raise InvalidInputError(f"colour must be (red, green, blue) in [0, 1], got {color!r}")
    return (values[0], values[1], values[2])


# --------------------------------------------------------------------------- model 2


class SurfaceSeries:
    """A surface known at instants and constant in between (model 2).

    Parameters
    ----------
    times : (k,) array_like of float
        The instants, strictly increasing and finite.
    surfaces : sequence of k Surface
        The shape at each instant, each with its own vertices, triangles and
        (for storage) the class's vertex or cell properties.
    properties : mapping of str to (k,) array_like, optional
        Per-instant feature properties (e.g. fault throw at each instant).
    alive : bool
        Whether the object still exists after its last instant (it keeps its
        last shape).
    name : str, optional
    color : (3,) sequence of float in [0, 1], optional

    Raises
    ------
    InvalidInputError, InvalidPropertyError
    """

    def __init__(
        self,
        times: npt.ArrayLike,
        surfaces: Sequence[Surface],
        *,
        properties: Mapping[str, npt.ArrayLike] | None = None,
        alive: bool = False,
        name: str | None = None,
        color: Sequence[float] | None = None,
    ) -> None:
        self.times = as_times(times, "instants of a surface series")
        self.surfaces = tuple(surfaces)
        if len(self.surfaces) != len(self.times) or not all(isinstance(s, Surface) for s in self.surfaces):
            raise InvalidInputError(
                f"a surface series needs one Surface per instant: {len(self.times)} instants, "
                f"{len(self.surfaces)} surfaces"
            )
        self.properties = as_series(properties, (len(self.times),), "per-instant property")
        self.alive = bool(alive)
        self.name = name
        self.color = _as_color(color)

    @property
    def start(self) -> float:
        """The first instant."""
        return float(self.times[0])

    @property
    def end(self) -> float:
        """The last instant (the object lasts for ever after it if alive)."""
        return float(self.times[-1])

    def instant_index(self, t: float, convention: Convention = "left") -> int | None:
        """Index of the instant whose surface holds at ``t``, or None when the object does not exist then."""
        t = check_time(t)
        check_convention(convention)
        if t < self.times[0]:
            return None
        if t > self.times[-1]:
            return len(self.times) - 1 if self.alive else None
        if convention == "left":
            return int(np.searchsorted(self.times, t, side="right")) - 1
        return int(np.searchsorted(self.times, t, side="left"))

    def at(self, t: float, convention: Convention = "left") -> Surface | None:
        """The surface at ``t`` (the stored Surface object of the chosen instant), or None."""
        index = self.instant_index(t, convention)
        return None if index is None else self.surfaces[index]

    def __repr__(self) -> str:
        return (
            f"SurfaceSeries({len(self.times)} instants {self.start!r}..{self.end!r}, alive={self.alive}, "
            f"name={self.name!r})"
        )


# --------------------------------------------------------------------------- model 3


@dataclass(frozen=True, eq=False)
class TopologyPeriod:
    """One topology period of an :class:`EvolvingSurface`: fixed triangles, moving nodes.

    Parameters
    ----------
    times : (g,) array_like of float
        Geometry instants of the period, strictly increasing; ``times[0]`` is
        where the period (and its topology) starts.
    triangles : (m, 3) array_like of int
        Node indices 0..n-1 of each triangle, the same through the period.
    positions : (g, n, 3) array_like of float
        Node coordinates at each geometry instant.
    vertex_properties : mapping of str to (g, n) array_like, optional
        Node values at each geometry instant (linear in between).
    cell_properties : mapping of str to (g, m) array_like, optional
        Triangle values at each geometry instant.
    properties : mapping of str to (g,) array_like, optional
        Per-instant feature properties at each geometry instant.

    Raises
    ------
    InvalidInputError, InvalidGeometryError, InvalidPropertyError
    """

    times: FloatArray
    triangles: IntArray
    positions: FloatArray
    vertex_properties: Mapping[str, npt.NDArray[np.generic]]
    cell_properties: Mapping[str, npt.NDArray[np.generic]]
    properties: Mapping[str, npt.NDArray[np.generic]]

    def __init__(
        self,
        times: npt.ArrayLike,
        triangles: npt.ArrayLike,
        positions: npt.ArrayLike,
        *,
        vertex_properties: Mapping[str, npt.ArrayLike] | None = None,
        cell_properties: Mapping[str, npt.ArrayLike] | None = None,
        properties: Mapping[str, npt.ArrayLike] | None = None,
    ) -> None:
        times_array = as_times(times, "geometry instants of a topology period")
        xyz = np.ascontiguousarray(positions, dtype=np.float64)
        if xyz.ndim != 3 or xyz.shape[0] != len(times_array) or xyz.shape[2] != 3:
            raise InvalidGeometryError(
                f"node positions must have shape (g, n, 3) with g = {len(times_array)} "
                f"geometry instants, got {xyz.shape}"
            )
        if not np.all(np.isfinite(xyz)):
            raise InvalidGeometryError("node positions must be finite (NaN or infinite coordinate found)")
        first = Surface(xyz[0], triangles)  # validates the triangles against the nodes
        g, n, m = len(times_array), xyz.shape[1], len(first.cells)
        object.__setattr__(self, "times", times_array)
        object.__setattr__(self, "triangles", first.cells)
        object.__setattr__(self, "positions", xyz)
        object.__setattr__(self, "vertex_properties", as_series(vertex_properties, (g, n), "vertex property"))
        object.__setattr__(self, "cell_properties", as_series(cell_properties, (g, m), "triangle property"))
        object.__setattr__(self, "properties", as_series(properties, (g,), "per-instant property"))

    @property
    def start(self) -> float:
        """Where the period starts (its topology instant)."""
        return float(self.times[0])

    @property
    def n_nodes(self) -> int:
        """Number of nodes n."""
        return int(self.positions.shape[1])

    @property
    def n_triangles(self) -> int:
        """Number of triangles m."""
        return len(self.triangles)

    def shape_at(self, j0: int, j1: int, w: float) -> Surface:
        """The surface between geometry instants ``j0 <= j1`` at weight ``w`` of the later one.

        Node positions and vertex/cell properties (as float64) are
        ``a + w * (b - a)``, the formula the SQL snapshot uses.
        """

        def mix(a: npt.NDArray[np.generic], b: npt.NDArray[np.generic]) -> FloatArray:
            a64, b64 = a.astype(np.float64), b.astype(np.float64)
            return a64 if j0 == j1 else a64 + w * (b64 - a64)

        return Surface(
            mix(self.positions[j0], self.positions[j1]),
            self.triangles,
            vertex_properties={k: mix(v[j0], v[j1]) for k, v in self.vertex_properties.items()},
            cell_properties={k: mix(v[j0], v[j1]) for k, v in self.cell_properties.items()},
        )


def sudden_change(
    before: Surface, period: TopologyPeriod, duration: float, *, label: str = "the period"
) -> TopologyPeriod:
    """``period`` starting in the shape ``before`` and reaching its own first shape ``duration`` later, linearly.

    The design's sudden change at a topology instant t0: the post-object
    (``period``, new topology) starts at t0 sharing the pre-object's
    geometry (``before``, the last shape of the period before) and changes
    linearly into its first shape, now at t0 + ``duration``. Its nodes start:
    at the nodes of ``before`` when it has as many and the same triangles
    (a motion); otherwise each at the closest point of ``before``'s
    triangles once the new shape's offset as a whole is taken out (a rigid
    offset is undone exactly: ``tgsis._transition.start_on``). Vertex, cell and per-instant properties keep their first
    values over the transition.

    Parameters
    ----------
    before : Surface
        The pre-object's shape at t0.
    period : TopologyPeriod
        Starting at t0; its second geometry instant (if any) after t0 + duration.
    duration : float
        Finite, > 0.
    label : str
        How messages name the period.

    Returns
    -------
    TopologyPeriod
        With g + 1 geometry instants.

    Raises
    ------
    InvalidInputError
        A bad duration, or one that does not end before the second instant.
    """
    times = transition_times(period.times, duration, label)
    if before.n_vertices == period.n_nodes and np.array_equal(before.cells, period.triangles):
        start = before.vertices.astype(np.float64)
    else:
        corners = before.vertices.astype(np.float64)
        start = start_on(lambda q: closest_on_triangles(corners, before.cells, q), period.positions[0])
    return TopologyPeriod(
        times,
        period.triangles,
        prepend_first(period.positions, start),
        vertex_properties={k: prepend_first(v) for k, v in period.vertex_properties.items()},
        cell_properties={k: prepend_first(v) for k, v in period.cell_properties.items()},
        properties={k: prepend_first(v) for k, v in period.properties.items()},
    )


class EvolvingSurface:
    """A surface evolving continuously, with topology changes at period starts (model 3).

    Parameters
    ----------
    periods : sequence of TopologyPeriod
        In time order. Each period but the last ends at the next one's start:
        its last geometry instant equals the next period's first (both hold a
        shape there, the new one applies from it on).
    alive : bool
        Whether the surface still exists after its last geometry instant.
    name : str, optional
    color : (3,) sequence of float in [0, 1], optional

    Raises
    ------
    InvalidInputError
        No period, or periods that do not follow each other.
    """

    def __init__(
        self,
        periods: Sequence[TopologyPeriod],
        *,
        alive: bool = False,
        name: str | None = None,
        color: Sequence[float] | None = None,
    ) -> None:
        self.periods = tuple(periods)
        if not self.periods or not all(isinstance(p, TopologyPeriod) for p in self.periods):
            raise InvalidInputError("an evolving surface needs at least one TopologyPeriod")
        for i, (a, b) in enumerate(zip(self.periods, self.periods[1:])):
            if a.times[-1] != b.times[0]:
                raise InvalidInputError(
                    f"topology period {i} must end where period {i + 1} starts: its last geometry instant is "
                    f"{a.times[-1]!r}, period {i + 1} starts at {b.times[0]!r}",
                    hint="a sudden change is a change over a very short period",
                )
        self.alive = bool(alive)
        self.name = name
        self.color = _as_color(color)
        self._starts = np.array([p.start for p in self.periods])

    @classmethod
    def constant(
        cls, surface: Surface, start: float, end: float, *, alive: bool = False, name: str | None = None
    ) -> EvolvingSurface:
        """A surface that stays as it is from ``start`` to ``end`` (one period, two geometry instants).

        Vertex and cell properties of ``surface`` are carried, constant too.

        Parameters
        ----------
        surface : Surface
        start, end : float
            ``start < end``.
        alive : bool
            Whether it exists after ``end``.
        """
        positions = np.stack([surface.vertices, surface.vertices])
        props = {k: np.stack([np.asarray(v), np.asarray(v)]) for k, v in surface.vertex_properties.items()}
        cells = {k: np.stack([np.asarray(v), np.asarray(v)]) for k, v in surface.cell_properties.items()}
        return cls(
            [TopologyPeriod([start, end], surface.cells, positions, vertex_properties=props, cell_properties=cells)],
            alive=alive,
            name=name if name is not None else surface.name,
        )

    @classmethod
    def chain(
        cls, parts: Sequence[EvolvingSurface], *, alive: bool | None = None, name: str | None = None
    ) -> EvolvingSurface:
        """One evolving surface over the whole life of consecutive ones (e.g. per-interval interpolations).

        Parameters
        ----------
        parts : sequence of EvolvingSurface
            In time order, each ending where the next starts.
        alive : bool, optional
            Default: the last part's.
        name : str, optional
            Default: the first part's.

        Raises
        ------
        InvalidInputError
            No parts, or parts that do not follow each other (named by position).
        """
        if not parts:
            raise InvalidInputError("chaining needs at least one evolving surface")
        for i, (a, b) in enumerate(zip(parts, parts[1:])):
            if a.end != b.start:
                raise InvalidInputError(
                    f"part {i} ends at {a.end!r} but part {i + 1} starts at {b.start!r}",
                    hint="chain parts that follow each other: each starts where the one before ends",
                )
        return cls(
            [p for part in parts for p in part.periods],
            alive=parts[-1].alive if alive is None else alive,
            name=name if name is not None else parts[0].name,
            color=parts[0].color,
        )

    def with_sudden_changes(self, duration: float) -> EvolvingSurface:
        """The same surface with every topology change made a short linear transition (:func:`sudden_change`).

        Each period after the first starts in the last shape of the one
        before and reaches its own first shape ``duration`` later; so a
        snapshot never jumps (the continuity rule of docs/time.md, "Topology
        changes"). ``tgsis.insert_feature(..., sudden_change=duration)`` stores this.
        """
        periods = [self.periods[0]]
        for i, period in enumerate(self.periods[1:], start=1):
            previous = self.periods[i - 1]
            last = len(previous.times) - 1
            periods.append(
                sudden_change(previous.shape_at(last, last, 0.0), period, duration, label=f"topology period {i}")
            )
        return EvolvingSurface(periods, alive=self.alive, name=self.name, color=self.color)

    @property
    def start(self) -> float:
        """The first topology instant."""
        return float(self.periods[0].times[0])

    @property
    def end(self) -> float:
        """The last geometry instant (the surface lasts for ever after it if alive)."""
        return float(self.periods[-1].times[-1])

    @property
    def topology_instants(self) -> FloatArray:
        """(k,) float64: where each period starts."""
        return self._starts.copy()

    @property
    def geometry_instants(self) -> FloatArray:
        """(G,) float64: every geometry instant, ascending, each once."""
        return np.unique(np.concatenate([p.times for p in self.periods]))

    @property
    def n_nodes(self) -> int:
        """Nodes over all periods."""
        return sum(p.n_nodes for p in self.periods)

    @property
    def n_triangles(self) -> int:
        """Triangles over all periods."""
        return sum(p.n_triangles for p in self.periods)

    def frame(self, t: float) -> Frame | None:
        """The period and bracketing geometry instants at ``t``, or None when the surface does not exist then."""
        return frame_at(self._starts, [p.times for p in self.periods], self.alive, t)

    def at(self, t: float) -> Surface | None:
        """The surface at ``t`` with its vertex/cell properties interpolated, or None when it does not exist."""
        frame = self.frame(t)
        if frame is None:
            return None
        surface = self.periods[frame.period].shape_at(frame.j0, frame.j1, frame.w)
        surface.name = self.name
        return surface

    def __repr__(self) -> str:
        return (
            f"EvolvingSurface({len(self.periods)} periods {self.start!r}..{self.end!r}, "
            f"{self.n_nodes} nodes, alive={self.alive}, name={self.name!r})"
        )


# --------------------------------------------------------------------------- time series export

#: A surface in time: known at instants (model 2) or evolving continuously (model 3).
TemporalSurface: TypeAlias = SurfaceSeries | EvolvingSurface
#: One sample of a surface in time: the time and the surface then (None: it does not exist then).
SurfaceFrame: TypeAlias = tuple[float, Surface | None]


def own_instants(obj: TemporalSurface) -> FloatArray:
    """(k,) float64: where ``obj`` is known, ascending (``SurfaceSeries.times``, ``EvolvingSurface.geometry_instants``)."""
    if isinstance(obj, SurfaceSeries):
        return obj.times.copy()
    if isinstance(obj, EvolvingSurface):
        return obj.geometry_instants
    raise InvalidInputError(f"expected a SurfaceSeries or an EvolvingSurface, got {type(obj).__name__}")


#: Most times :func:`even_times` gives: each becomes a frame (a file, for a ParaView series).
MAX_STEPS = 100_000


def even_times(
    start: float, end: float, steps: int, *, labels: tuple[str, str, str] = ("start", "end", "steps")
) -> FloatArray:
    """``steps`` times evenly spaced from ``start`` to ``end``, both included (exactly).

    Parameters
    ----------
    start, end : float
        Finite, ``start <= end``; equal only for one step.
    steps : int
        At least 1 and at most :data:`MAX_STEPS`; 1 only when ``start == end``.
    labels : (str, str, str)
        How error messages name the three arguments (e.g. command-line options).

    Raises
    ------
    InvalidInputError
        Any of the conditions above, or so many steps that neighbouring times
        are the same float.
    """
    first, last, count = labels
    if not isinstance(steps, numbers.Integral) or isinstance(steps, bool) or steps < 1:
        raise InvalidInputError(f"{count} must be an integer >= 1, got {steps!r}")
    if steps > MAX_STEPS:  # 1e11 steps asked for 745 GiB of times before a single frame was written
        raise InvalidInputError(
            f"{count} {steps} is too many: at most {MAX_STEPS} times (one frame file each)",
            hint=f"give {count} {MAX_STEPS} or fewer",
        )
    for label, value in ((first, start), (last, end)):
        if not isinstance(value, numbers.Real) or isinstance(value, bool) or not np.isfinite(float(value)):
            raise InvalidInputError(f"{label} must be a finite number, got {value!r}")
    a, b, n = float(start), float(end), int(steps)
    if a > b:
        raise InvalidInputError(f"{first} ({a!r}) must not be after {last} ({b!r})")
    if n == 1 and a != b:
        raise InvalidInputError(
            f"{count} 1 gives one time, so {first} and {last} must be equal, got {a!r} and {b!r}",
            hint=f"{count} 2 gives just the two ends",
        )
    if n > 1 and a == b:
        raise InvalidInputError(
            f"{count} {n} needs {first} before {last}: both are {a!r}", hint=f"{count} 1 gives the one time"
        )
    times = np.linspace(a, b, n)
    if n > 1 and not np.all(np.diff(times) > 0):
        raise InvalidInputError(f"{n} {count} between {a!r} and {b!r} give equal neighbouring times (float precision)")
    return times


def series_frames(
    obj: TemporalSurface, times: npt.ArrayLike | None = None, convention: Convention = "left"
) -> list[SurfaceFrame]:
    """The surface of ``obj`` at each time: ``[(t, obj.at(t) or None), ...]``.

    Parameters
    ----------
    obj : SurfaceSeries or EvolvingSurface
    times : (k,) array_like of float, optional
        Finite and strictly increasing (as a ``.pvd`` needs them); by default
        the object's own instants (:func:`own_instants`).
    convention : {"left", "right"}
        Step convention of a SurfaceSeries (an EvolvingSurface has none).

    Returns
    -------
    list of (float, Surface or None)
        None where the object does not exist. A SurfaceSeries gives its
        stored Surface objects (with their properties); an EvolvingSurface
        new ones with interpolated properties.

    Raises
    ------
    InvalidInputError
    """
    check_convention(convention)
    samples = own_instants(obj) if times is None else as_times(times, "sample times")
    if isinstance(obj, SurfaceSeries):
        return [(t, obj.at(t, convention)) for t in samples.tolist()]
    return [(t, obj.at(t)) for t in samples.tolist()]


@dataclass(frozen=True)
class WrittenSeries:
    """What a time-series export wrote.

    Attributes
    ----------
    pvd : Path
        The ``.pvd`` file.
    files : tuple of Path
        The ``.vtu`` frame files, one per frame, in time order.
    frames : tuple of (float, Surface or None)
        The time and surface of each frame (None: written as an empty grid).
    """

    pvd: Path
    files: tuple[Path, ...]
    frames: tuple[SurfaceFrame, ...]

    @property
    def missing(self) -> list[float]:
        """Times of the frames without an object."""
        return [t for t, surface in self.frames if surface is None]


def write_frames_pvd(frames: Sequence[SurfaceFrame], path: PathLike, *, encoding: Encoding = "binary") -> WrittenSeries:
    """Write surface frames with :func:`tgsis.formats.pvd.write_pvd`; return what was written."""
    written = write_pvd(frames, path, encoding=encoding)
    return WrittenSeries(written[-1], tuple(written[:-1]), tuple(frames))


def write_series_pvd(
    obj: TemporalSurface,
    path: PathLike,
    times: npt.ArrayLike | None = None,
    *,
    convention: Convention = "left",
    encoding: Encoding = "binary",
) -> WrittenSeries:
    """Write a surface in time as a ParaView ``.pvd`` time series, one ``.vtu`` frame per time.

    Parameters
    ----------
    obj : SurfaceSeries or EvolvingSurface
    path : str or path-like
        The ``.pvd`` file; frames go to ``<stem>/<stem>_000000.vtu``, ...
        beside it (see :func:`tgsis.formats.pvd.write_pvd`).
    times : (k,) array_like of float, optional
        Sample times, finite and strictly increasing; by default the object's
        own instants (where a model-3 surface's trajectories bend, where a
        model-2 surface steps). :func:`even_times` spaces them evenly.
    convention : {"left", "right"}
        Step convention of a SurfaceSeries.
    encoding : {"binary", "appended"}
        Of the ``.vtu`` files.

    Returns
    -------
    WrittenSeries

    Raises
    ------
    InvalidInputError, FileFormatError
    """
    return write_frames_pvd(series_frames(obj, times, convention), path, encoding=encoding)


# --------------------------------------------------------------------------- answers of temporal questions


@dataclass(frozen=True)
class Period:
    """An interval of model time, as ``tgsis.property_periods`` returns them.

    Parameters
    ----------
    start, end : float
        Bounds, ``start <= end``; ``-inf`` / ``inf`` for an unbounded end
        (an alive feature keeps its last value for ever).
    start_closed, end_closed : bool
        Whether the bound itself belongs to the interval (always False for an
        infinite bound). ``Period(t, t, True, True)`` is the single instant t.

    Examples
    --------
    >>> p = Period(1.0, 2.0, True, False)   # [1, 2)
    >>> 1.0 in p, 2.0 in p, str(p)
    (True, False, '[1.0, 2.0)')
    """

    start: float
    end: float
    start_closed: bool
    end_closed: bool

    def __contains__(self, t: object) -> bool:
        """Whether model time ``t`` lies in the interval (NaN never does)."""
        if not isinstance(t, (int, float, np.floating, np.integer)):
            return False
        value = float(t)
        after_start = self.start < value or (self.start_closed and value == self.start)
        before_end = value < self.end or (self.end_closed and value == self.end)
        return after_start and before_end

    def __str__(self) -> str:
        return f"{'[' if self.start_closed else '('}{self.start!r}, {self.end!r}{']' if self.end_closed else ')'}"
