"""Array types and the checked point array shared by the G-map modules (:mod:`tgsis.gmaps._core`, ``_build``)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from tgsis.errors import InvalidGMapError

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


def as_points(points: npt.ArrayLike, what: str = "points", one: str = "point") -> FloatArray:
    try:
        array = np.ascontiguousarray(points, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise InvalidGMapError(f"{what} are not numbers: {exc}") from None
    if array.ndim != 2:
        raise InvalidGMapError(f"{what} must be a (k, m) array, got shape {array.shape}")
    bad = ~np.isfinite(array)
    if bad.any():
        row, col = (int(v) for v in np.argwhere(bad)[0])
        raise InvalidGMapError(
            f"{one} {row} has a non-finite coordinate {col} ({array[row, col]})",
            detail=f"{int(bad.any(axis=1).sum())} {what} have NaN or infinite coordinates",
        )
    return array
