"""Checks of the arguments of the public database functions, before anything reaches the server.

Without them a wrong argument came back as a raw PostgreSQL error that names
no argument: ``22P02`` (``"abc"`` for an integer), ``42883`` (an integer too
large for the SQL parameter, so that psycopg sends a ``bigint`` or ``numeric``
and no function matches), or psycopg's own "PostgreSQL text fields cannot
contain NUL (0x00) bytes" with no SQLSTATE at all. :func:`checked`, the decorator of
every public database function (tests/test_public_api.py), makes such arguments raise
:class:`~tgsis.errors.InvalidInputError` naming the parameter, from the type
hints of the function:

* ``str`` parameters (also inside sequences and mappings): no NUL byte; a
  parameter that only takes ``str`` must get one (or ``None``, which the
  function's own checks refuse where it is not allowed);
* ``int`` parameters: an integer (not ``bool``) in the range of the SQL
  parameter: ``integer`` for revisions, orders and SRS ids
  (:data:`INT4_PARAMETERS`), else ``bigint``;
* ``float`` parameters: a real number (not ``bool`` or ``str``).

The wrappers keep the signature and docstring (:func:`functools.wraps`).
"""

from __future__ import annotations

import functools
import inspect
import numbers
import types
import typing
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeVar, cast

from tgsis.errors import InvalidInputError

__all__ = ["checked", "checked_ids", "no_nul", "INT4_PARAMETERS"]

#: Parameters whose SQL counterpart is ``integer`` (4 bytes) rather than ``bigint``.
INT4_PARAMETERS = frozenset({"revision", "a_revision", "b_revision", "iudorder", "srs"})

_INT8 = (-(2**63), 2**63 - 1)
_INT4 = (-(2**31), 2**31 - 1)


def _kinds(hint: Any) -> frozenset[str]:
    """What a type hint admits, coarsely: str, int, float, none, seq, map, other."""
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        return frozenset().union(*(_kinds(arg) for arg in typing.get_args(hint)))
    if hint is str:
        return frozenset({"str"})
    if hint is bool:
        return frozenset({"other"})
    if hint is int:
        return frozenset({"int"})
    if hint is float:
        return frozenset({"float"})
    if hint is type(None):
        return frozenset({"none"})
    if origin in (list, tuple, set, frozenset, Sequence, Iterable) or hint in (list, tuple):
        return frozenset({"seq"})
    if origin in (dict, Mapping) or hint is dict:
        return frozenset({"map"})
    return frozenset({"other"})


def _nul(name: str, value: str) -> InvalidInputError:
    return InvalidInputError(
        f"{name} contains a NUL byte (at character {value.index(chr(0))}), which PostgreSQL text cannot hold",
        hint=f"remove the \\x00 from {name}",
    )


def _check_text(name: str, value: Any) -> None:
    """NUL bytes in a string, or in the strings of a sequence or mapping (one level)."""
    if isinstance(value, str):
        if "\x00" in value:
            raise _nul(name, value)
    elif isinstance(value, Mapping):
        for key, item in value.items():
            if isinstance(key, str) and "\x00" in key:
                raise _nul(f"a key of {name}", key)
            if isinstance(item, str) and "\x00" in item:
                raise _nul(f"{name}[{key!r}]", item)
    elif isinstance(value, (list, tuple, set, frozenset)):
        for index, item in enumerate(value):
            if isinstance(item, str) and "\x00" in item:
                raise _nul(f"{name}[{index}]", item)


def no_nul(name: str, value: str | None) -> str | None:
    """``value`` unchanged, or :class:`InvalidInputError` naming ``name`` if it holds a NUL byte.

    For text that reaches PostgreSQL without being a parameter of a public
    function, e.g. the name a mesh read from a file carries.
    """
    if value is not None and "\x00" in value:
        raise _nul(name, value)
    return value


def checked_ids(name: str, values: Iterable[Any]) -> list[int]:
    """Object ids of a sequence: integers (not bool, not 1.5) in the range of ``bigint``, else :class:`InvalidInputError`.

    ``int(1.5)`` is 1: an id that is no integer is refused rather than
    taken for another object.
    """
    ids: list[int] = []
    for index, value in enumerate(values):
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidInputError(
                f"{name}[{index}] must be an integer id, not {type(value).__name__} {repr(value)[:100]}"
            )
        if not _INT8[0] <= int(value) <= _INT8[1]:
            raise InvalidInputError(
                f"{name}[{index}] = {str(int(value))[:100]} is out of range: it must be from {_INT8[0]} to {_INT8[1]}"
            )
        ids.append(int(value))
    return ids


def _check(name: str, kinds: frozenset[str], value: Any) -> None:
    _check_text(name, value)
    if value is None:  # NULL where a value is needed: the function's own check says which (e.g. TG101 for names)
        return
    if kinds <= {"str", "none"} and not isinstance(value, str):
        raise InvalidInputError(f"{name} must be a string, not {type(value).__name__} {value!r}")
    if kinds <= {"int", "none"}:
        if isinstance(value, bool) or not isinstance(value, numbers.Integral):
            raise InvalidInputError(f"{name} must be an integer, not {type(value).__name__} {value!r}")
        low, high = _INT4 if name in INT4_PARAMETERS else _INT8
        if not low <= int(value) <= high:
            raise InvalidInputError(f"{name} = {int(value)} is out of range: it must be from {low} to {high}")
    elif kinds <= {"float", "int", "none"} and "float" in kinds:
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise InvalidInputError(f"{name} must be a number, not {type(value).__name__} {value!r}")


_F = TypeVar("_F", bound=Callable[..., Any])


def checked(func: _F) -> _F:
    """Wrap ``func`` so that its arguments are checked from its type hints first (see the module).

    The wrapper has the signature of ``func`` for type checkers too (a decorator typed
    ``Callable[..., Any]`` would turn every public function into ``Any`` for users' mypy).
    """
    try:
        hints = typing.get_type_hints(func)
    except Exception:  # noqa: BLE001 - a hint that cannot be resolved: nothing to check by
        return func
    signature = inspect.signature(func)
    plan = {name: _kinds(hints[name]) for name in signature.parameters if name in hints and name != "conn"}
    plan = {name: kinds for name, kinds in plan.items() if kinds & {"str", "int", "float", "seq", "map"}}
    if not plan:  # nothing to check (only a connection, booleans, objects): marked all the same
        func.__tgsis_checked__ = True  # type: ignore[attr-defined]
        return func

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            bound = signature.bind(*args, **kwargs)
        except TypeError:
            return func(*args, **kwargs)  # let Python say what is wrong with the call
        for name, value in bound.arguments.items():
            kinds = plan.get(name)
            if kinds is not None:
                _check(name, kinds, value)
        return func(*args, **kwargs)

    wrapper.__tgsis_checked__ = True  # type: ignore[attr-defined]
    return cast(_F, wrapper)
