"""What two tries of a read must share to count as one state (tgsis.db._same_result): bit for bit, else different."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tgsis.db._same_result import same_result


@dataclass
class Box:
    name: str
    values: np.ndarray


class Slotted:
    __slots__ = ("a", "b")

    def __init__(self, a: object, b: object | None = None) -> None:
        self.a = a
        if b is not None:
            self.b = b


class Opaque:
    """No attributes to compare, no __eq__: never the same as another one."""

    __slots__ = ()


def test_floats_bit_for_bit() -> None:
    assert same_result(1.5, 1.5)
    assert not same_result(0.0, -0.0)
    assert same_result(math.nan, math.nan)
    assert not same_result(1.0, 1)  # a float and an int: not the same type
    assert same_result(np.float64(2.0), np.float64(2.0))
    assert not same_result(np.float64(0.0), np.float64(-0.0))


def test_arrays_by_dtype_shape_and_bytes() -> None:
    a = np.array([[0.0, np.nan], [1.0, 2.0]])
    assert same_result(a, a.copy())
    assert same_result(a, np.asfortranarray(a))
    assert not same_result(a, a.astype(np.float32))
    assert not same_result(a, a.reshape(4))
    b = a.copy()
    b[1, 1] = np.nextafter(2.0, 3.0)
    assert not same_result(a, b)
    c = a.copy()
    c[1, 0] = -0.0
    d = a.copy()
    d[1, 0] = 0.0
    assert not same_result(c, d)
    objects = np.array([{"x": 1.0}, None], dtype=object)
    assert same_result(objects, np.array([{"x": 1.0}, None], dtype=object))
    assert not same_result(objects, np.array([{"x": -1.0}, None], dtype=object))


def test_containers_and_objects() -> None:
    assert same_result({"a": [1, (2.0, "x")], "b": None}, {"b": None, "a": [1, (2.0, "x")]})
    assert not same_result({"a": 1}, {"a": 1, "b": 2})
    assert not same_result([1, 2], (1, 2))
    assert not same_result([1, 2], [1, 2, 3])
    assert same_result(Box("t", np.arange(3.0)), Box("t", np.arange(3.0)))
    assert not same_result(Box("t", np.arange(3.0)), Box("u", np.arange(3.0)))
    assert same_result(Slotted(1.0, "x"), Slotted(1.0, "x"))
    assert not same_result(Slotted(1.0, "x"), Slotted(1.0))  # one attribute unset
    assert not same_result(Slotted(0.0), Slotted(-0.0))
    assert same_result(memoryview(b"ab"), memoryview(b"ab"))
    assert {1, 2} == {2, 1} and same_result({1, 2}, {2, 1})


def test_the_values_of_property_types_psycopg_returns() -> None:
    """numeric, date and timestamptz properties come as Decimal and datetime (C types: no attributes to walk)."""
    from datetime import date, datetime, timedelta, timezone
    from decimal import Decimal

    assert same_result(Decimal("1.50"), Decimal("1.50"))
    assert not same_result(Decimal("1.5"), Decimal("1.50"))  # equal numbers, other scales: not the same value read
    assert same_result(Decimal("NaN"), Decimal("NaN"))
    assert not same_result(Decimal("0"), Decimal("-0"))
    assert same_result(date(2026, 12, 7), date(2026, 12, 7))
    assert not same_result(date(2026, 12, 7), date(2026, 12, 8))
    utc = datetime(2026, 12, 7, 1, 0, tzinfo=timezone.utc)
    assert same_result({"t": utc}, {"t": datetime(2026, 12, 7, 1, 0, tzinfo=timezone.utc)})
    assert not same_result(utc, utc.astimezone(timezone(timedelta(hours=1))))  # the same instant, another zone


def test_what_cannot_be_compared_is_different() -> None:
    one = Opaque()
    assert same_result(one, one)  # the very same object
    assert not same_result(one, Opaque())
