"""The continuity check of topology changes (models 3 and 4) on the write paths of the Python client.

Every path that stores topology periods (``insert_feature`` of an
EvolvingSurface or EvolvingGMap, ``append_period``) calls
``tgsis.check_period_continuity`` in its transaction after the rows are in,
so that the check is the database's own (the same one plain-SQL writers
call) and a refused write leaves nothing behind. The error keeps the
server's message and detail and gets a hint in Python's terms.
"""

from __future__ import annotations

import math
from typing import Any

import psycopg

from tgsis.errors import DiscontinuousPeriodsError, InvalidInputError

Conn = psycopg.Connection[Any]

#: What a refused write may do instead, in the words of the Python API.
HINT = (
    "start the new period on the last shape of the one before, allow a larger gap with the tolerance argument, "
    "or store the change as a short linear transition with the sudden_change argument (docs/time.md, Topology changes)"
)


def checked_tolerance(tolerance: float | None) -> float | None:
    """``tolerance`` as a float, None kept; InvalidInputError unless finite and >= 0."""
    if tolerance is None:
        return None
    value = float(tolerance)
    if not math.isfinite(value) or value < 0:
        raise InvalidInputError(f"the tolerance of topology changes must be a finite distance >= 0, got {tolerance!r}")
    return value


def check_continuity(conn: Conn, geoid: int, tolerance: float | None, start: float | None = None) -> None:
    """Raise DiscontinuousPeriodsError when a stored period (from ``start`` on) jumps; inside the caller's transaction."""
    try:
        with conn.transaction():
            conn.execute("SELECT tgsis.check_period_continuity(%s, %s, %s)", (geoid, tolerance, start))
    except psycopg.Error as exc:
        if exc.sqlstate != DiscontinuousPeriodsError.code:
            raise
        diag = exc.diag
        raise DiscontinuousPeriodsError(
            diag.message_primary or str(exc), detail=diag.message_detail, hint=HINT
        ) from exc
