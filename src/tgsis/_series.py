"""Checked instants and per-instant values shared by the numpy temporal types (models 2 to 4)."""

from __future__ import annotations

from collections.abc import Mapping

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


def as_series(values: Mapping[str, npt.ArrayLike] | None, shape: tuple[int, ...],
               what: str) -> dict[str, npt.NDArray[np.generic]]:
    """Numeric arrays of exactly ``shape`` under valid property names."""
    result: dict[str, npt.NDArray[np.generic]] = {}
    for name, raw in (values or {}).items():
        if not PROPERTY_NAME_RE.match(name):
            raise InvalidPropertyError(f"{what} name {name!r} is not allowed (letters, digits, _; starting with a letter)")
        array = np.ascontiguousarray(raw)
        if array.dtype.kind not in "biuf":
            raise InvalidPropertyError(f"{what} {name!r} must be numeric or boolean, got {array.dtype}")
        if array.shape != shape:
            raise InvalidPropertyError(f"{what} {name!r} must have shape {shape}, got {array.shape}")
        result[name] = array
    return result
