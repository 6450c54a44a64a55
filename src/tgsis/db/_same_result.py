"""Whether two results of one read are the same, bit for bit: what a read of several statements may trust.

:func:`tgsis.db._transfer.consistent_read` runs a read again when other sessions committed during it
(under ``READ COMMITTED`` each statement sees what was committed before it). Most such commits change
nothing the read reads: another database's, autovacuum's ``ANALYZE`` (it writes ``pg_statistic``),
another application's. Two consecutive tries that read the same thing tell it: each try's statements
saw the same rows, so the result is one state's. Anything this module cannot compare (an object
without a way to say it equals another) counts as different: the read is run again rather than trusted.
"""

from __future__ import annotations

import dataclasses
import datetime
import decimal
import struct
import uuid
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["same_result"]

_PLAIN = (str, bytes, bytearray, memoryview, int, bool, type(None), complex)
# values of the class properties' SQL types (numeric, date, timestamptz) and others psycopg returns, compared by
# repr: exact (Decimal('NaN') and Decimal('-0'), a datetime's time zone), where == is not
_BY_REPR = (decimal.Decimal, datetime.date, datetime.time, datetime.timedelta, uuid.UUID)


def same_result(a: Any, b: Any) -> bool:
    """True when ``a`` and ``b`` hold the same values, floats and arrays bit for bit (NaN payloads, -0.0).

    Walks tuples, lists, dicts (keys as a set, their values), sets, numpy arrays (dtype, shape and
    bytes; object arrays element by element), dataclasses and objects with ``__dict__`` or
    ``__slots__``. Types must match exactly.
    """
    if a is b:
        return True
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return _same_array(a, b)
    if isinstance(a, float | np.floating):
        return _bits(a) == _bits(b)
    if isinstance(a, _PLAIN) or isinstance(a, np.generic):
        return bool(a == b)
    if isinstance(a, _BY_REPR):
        return repr(a) == repr(b)
    if isinstance(a, tuple | list):
        return len(a) == len(b) and all(same_result(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, Mapping):
        return a.keys() == b.keys() and all(same_result(a[k], b[k]) for k in a)
    if isinstance(a, set | frozenset):
        return bool(a == b)
    if dataclasses.is_dataclass(a):
        return all(same_result(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a))
    return _same_attributes(a, b)


def _bits(x: Any) -> bytes:
    """The float's bytes: 0.0 and -0.0 differ, a NaN equals the same NaN."""
    if isinstance(x, np.floating):
        return x.tobytes()
    return struct.pack("<d", x)


def _same_array(a: np.ndarray[Any, Any], b: np.ndarray[Any, Any]) -> bool:
    if a.dtype != b.dtype or a.shape != b.shape:
        return False
    if a.dtype.hasobject:
        return all(same_result(x, y) for x, y in zip(a.ravel(), b.ravel(), strict=True))
    return np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes()


def _same_attributes(a: Any, b: Any) -> bool:
    """Objects by their attributes; one with neither ``__dict__`` nor ``__slots__`` is never the same."""
    names: list[str] = []
    for klass in type(a).__mro__:
        slots = klass.__dict__.get("__slots__", ())
        names.extend([slots] if isinstance(slots, str) else slots)
    if not hasattr(a, "__dict__") and not names:
        return False
    if hasattr(a, "__dict__") and not same_result(vars(a), vars(b)):
        return False
    for name in names:
        if name in ("__dict__", "__weakref__"):
            continue
        if hasattr(a, name) != hasattr(b, name):
            return False
        if hasattr(a, name) and not same_result(getattr(a, name), getattr(b, name)):
            return False
    return True
