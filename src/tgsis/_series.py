"""Checked instants and per-instant values shared by the numpy temporal types (models 2 to 4)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidInputError, InvalidPropertyError
from tgsis.mesh import PROPERTY_NAME_RE

FloatArray = npt.NDArray[np.float64]


def as_times(times: npt.ArrayLike, what: str) -> FloatArray:
    """(k,) float64 instants, finite and strictly increasing, at least one."""
    array = np.ascontiguousarray(times, dtype=np.float64)
    if array.ndim != 1 or len(array) == 0:
        raise InvalidInputError(f"{what} must be a non-empty list of instants, got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise InvalidInputError(f"{what} must be finite numbers, got {array[~np.isfinite(array)][0]!r}")
    steps = np.diff(array)
    if np.any(steps <= 0):
        bad = int(np.argmax(steps <= 0))
        raise InvalidInputError(f"{what} must be strictly increasing: {array[bad]!r} then {array[bad + 1]!r}")
    return array


def as_series(
    values: Mapping[str, npt.ArrayLike] | None, shape: tuple[int, ...], what: str
) -> dict[str, npt.NDArray[np.generic]]:
    """Numeric arrays of exactly ``shape`` under valid property names."""
    result: dict[str, npt.NDArray[np.generic]] = {}
    for name, raw in (values or {}).items():
        if not PROPERTY_NAME_RE.match(name):
            raise InvalidPropertyError(
                f"{what} name {name!r} is not allowed (letters, digits, _; starting with a letter)"
            )
        array = np.ascontiguousarray(raw)
        if array.dtype.kind not in "biuf":
            raise InvalidPropertyError(f"{what} {name!r} must be numeric or boolean, got {array.dtype}")
        if array.shape != shape:
            raise InvalidPropertyError(f"{what} {name!r} must have shape {shape}, got {array.shape}")
        result[name] = array
    return result


def check_time(t: float) -> float:
    """``t`` as a float; :class:`~tgsis.errors.InvalidInputError` for NaN (infinities mean before/after all)."""
    value = float(t)
    if np.isnan(value):
        raise InvalidInputError("model time NaN is not a time")
    return value


@dataclass(frozen=True)
class Frame:
    """Where a time falls in an :class:`EvolvingSurface`: period index, bracketing instants j0 <= j1, weight."""

    period: int
    j0: int
    j1: int
    w: float


def frame_at(starts: FloatArray, period_times: Sequence[FloatArray], alive: bool, t: float) -> Frame | None:
    """Where ``t`` falls in an object with topology periods (models 3 and 4), or None when it does not exist then.

    Parameters
    ----------
    starts : (k,) float64
        Where each period starts, ascending.
    period_times : sequence of (g_i,) float64
        The geometry instants of each period; ``period_times[i][0] == starts[i]``.
    alive : bool
        Whether the object exists after its last geometry instant (in its last state).
    t : float

    Notes
    -----
    The period is the last one starting at or before ``t`` (at a topology
    change the new topology applies); nothing before the first start, nor
    after the last geometry instant unless alive. The same rules as the SQL
    snapshots (``tgsis.evolving_frame``, ``tgsis.gmap_frame``).
    """
    t = check_time(t)
    if t < starts[0]:
        return None
    index = int(np.searchsorted(starts, t, side="right")) - 1
    times = period_times[index]
    if t > times[-1]:
        last = len(times) - 1
        return Frame(index, last, last, 0.0) if alive or index < len(period_times) - 1 else None
    j1 = int(np.searchsorted(times, t, side="left"))
    if times[j1] == t:
        return Frame(index, j1, j1, 0.0)
    j0 = j1 - 1
    return Frame(index, j0, j1, float((t - times[j0]) / (times[j1] - times[j0])))
