"""Exact matching of rows between two meshes: the machinery of mesh comparison (:mod:`tgsis.compare`).

Rows (coordinate triples, oriented cells as sorted vertex ids and a parity
bit) are hashed to 64 bits, both sides sorted by hash and merged with
``searchsorted``; every candidate pair is verified for exact equality, so a
hash collision never makes a false match. Shared by :mod:`tgsis.compare`
and :mod:`tgsis.edits`; pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

IntArray = npt.NDArray[np.int64]
U64Array = npt.NDArray[np.uint64]

# odd 64-bit constants of splitmix64 / murmur3's finaliser: good avalanche, wrap-around arithmetic
_MULTIPLIERS = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB))


def _mix(h: U64Array) -> U64Array:
    """splitmix64's finaliser, in place on a fresh array."""
    h ^= h >> np.uint64(30)
    h *= _MULTIPLIERS[1]
    h ^= h >> np.uint64(27)
    h *= _MULTIPLIERS[2]
    h ^= h >> np.uint64(31)
    return h


def row_hashes(columns: list[U64Array]) -> U64Array:
    """A 64-bit hash of each row of k equal-length uint64 columns."""
    h = np.full(len(columns[0]), _MULTIPLIERS[0], dtype=np.uint64)
    for column in columns:
        h ^= column
        h = _mix(h)
    return h


def coordinate_columns(vertices: npt.NDArray[np.float64]) -> list[U64Array]:
    """The bits of the x, y and z coordinates, with ``-0.0`` made ``0.0`` (equal numbers, equal bits)."""
    return [
        (np.ascontiguousarray(vertices[:, j], dtype=np.float64) + 0.0).view(np.uint64)  # -0.0 + 0.0 == +0.0
        for j in range(3)
    ]


# Sorting (hash << 32 | row index) with np.sort is 2.5-3.4 times as fast as
# np.argsort of the hashes (measured: docs/performance.md): the order comes
# out of the low bits. Rows whose 32-bit hash prefixes collide are paired
# exactly by _match_crowded.
_INDEX_BITS = np.uint64(32)


_LOW = np.uint64((1 << 32) - 1)


@dataclass(frozen=True)
class SortedRows:
    """Rows (as k uint64 columns) in the order of their hashes, so that many comparisons can reuse them."""

    columns: list[U64Array]
    order: IntArray
    sorted_hashes: U64Array
    sorted_columns: list[U64Array]

    @classmethod
    def of(cls, columns: list[U64Array]) -> SortedRows:
        hashes = row_hashes(columns)
        n = len(hashes)
        if n <= int(_LOW):
            keys = (hashes & ~_LOW) | np.arange(n, dtype=np.uint64)
            keys.sort()
            order = (keys & _LOW).view(np.int64)
            prefixes = keys >> _INDEX_BITS
        else:  # beyond 2**32 rows the index does not fit in the low bits
            order = np.argsort(hashes)
            prefixes = hashes[order] >> _INDEX_BITS
        # one column: the hash is a bijection of it (xor and splitmix's steps are invertible), so the
        # sorted full hashes verify a match exactly; several columns are compared value by value
        sorted_columns = [hashes[order]] if len(columns) == 1 else [c[order] for c in columns]
        return cls(columns, order, prefixes, sorted_columns)

    def __len__(self) -> int:
        return len(self.order)

    @cached_property
    def unique_hash(self) -> npt.NDArray[np.bool_]:
        """Per sorted position: whether no other row has the same hash prefix (kept: an index is reused)."""
        s = self.sorted_hashes
        alone = np.ones(len(s), dtype=bool)
        if len(s) > 1:
            same = s[1:] == s[:-1]
            alone[1:] &= ~same
            alone[:-1] &= ~same
        return alone


def match_rows(old: SortedRows, new: SortedRows) -> IntArray:
    """For each row of ``new``, the index of the equal row of ``old`` (one-to-one), or -1.

    Equal rows are paired in index order when either side repeats a row (not
    a normal mesh) or different rows share a hash prefix (a collision).
    """
    result = np.full(len(new), -1, dtype=np.int64)
    if len(old) == 0 or len(new) == 0:
        return result
    pos = np.searchsorted(old.sorted_hashes, new.sorted_hashes)  # queries in sorted order: a merge
    np.minimum(pos, len(old) - 1, out=pos)
    same_hash = old.sorted_hashes[pos] == new.sorted_hashes
    simple = same_hash & old.unique_hash[pos] & new.unique_hash
    at = pos[simple]  # both sides read in hash order: sequential memory access
    exact = np.ones(len(at), dtype=bool)
    for old_column, new_column in zip(old.sorted_columns, new.sorted_columns):
        exact &= old_column[at] == new_column[simple]
    result[new.order[simple][exact]] = old.order[at[exact]]
    crowded = same_hash & ~simple  # a hash shared by several rows of one side: pair exactly, in index order
    if crowded.any():
        _match_crowded(old, new, np.unique(new.sorted_hashes[crowded]), result)
    return result


def _match_crowded(old: SortedRows, new: SortedRows, hashes: U64Array, result: IntArray) -> None:
    """Pair the rows whose hash prefix is one of ``hashes`` by exact value (rare: collisions, repeated rows)."""

    def rows_with(side: SortedRows) -> IntArray:
        lo = np.searchsorted(side.sorted_hashes, hashes, side="left")
        hi = np.searchsorted(side.sorted_hashes, hashes, side="right")
        return np.sort(np.concatenate([side.order[a:b] for a, b in zip(lo.tolist(), hi.tolist())]))

    def row(side: SortedRows, i: int) -> tuple[int, ...]:
        return tuple(int(c[i]) for c in side.columns)

    waiting: dict[tuple[int, ...], list[int]] = {}
    for i in rows_with(old).tolist():
        waiting.setdefault(row(old, i), []).append(i)
    for taken in waiting.values():
        taken.reverse()  # pop() from the end hands out the lowest index first
    for j in rows_with(new).tolist():
        queue = waiting.get(row(new, j))
        if queue:
            result[j] = queue.pop()


def _permutation_parity(columns: list[IntArray]) -> npt.NDArray[np.uint64]:
    """0 for cells whose vertex order is an even permutation of the ascending order, 1 for odd (inversions)."""
    odd = np.zeros(len(columns[0]), dtype=bool)
    for i, first in enumerate(columns):
        for second in columns[i + 1 :]:
            odd ^= first > second
    return odd.view(np.uint8).astype(np.uint64)


def columns_of(cells: IntArray) -> list[IntArray]:
    """The k columns of an (m, k) cell array, each contiguous."""
    return [np.ascontiguousarray(cells[:, i]) for i in range(cells.shape[1])]


def cell_columns(columns: list[IntArray], n_vertices: int) -> list[U64Array]:
    """Oriented cells, given as their k columns of vertex ids, as rows: sorted ids and the parity of the order.

    When k ids of ``n_vertices`` and the parity bit fit in 64 bits (a
    surface of up to 2M vertices) they are packed into one exact key.
    """
    k = len(columns)
    if k == 1:
        return [columns[0].astype(np.uint64)]
    bits = max(1, (max(n_vertices, 1) - 1).bit_length())
    ids = [c.view(np.uint64) for c in columns]  # ids >= 0: the same order as int64
    if k == 2:
        ordered = [np.minimum(ids[0], ids[1]), np.maximum(ids[0], ids[1])]
    elif k == 3:  # a sorting network on contiguous columns (3x faster than np.sort along rows)
        a, b, c = ids
        low, high = np.minimum(np.minimum(a, b), c), np.maximum(np.maximum(a, b), c)
        ordered = [low, a + b + c - low - high, high]  # ids < 2**63: no overflow
    else:
        sorted_cells = np.sort(np.stack(ids, axis=1), axis=1)
        ordered = [np.ascontiguousarray(sorted_cells[:, i]) for i in range(k)]
    parity = _permutation_parity(columns)
    if k * bits + 1 > 64:
        return [*ordered, parity]
    key = ordered[0].copy()
    for column in ordered[1:]:
        key <<= np.uint64(bits)
        key |= column
    key <<= np.uint64(1)
    key |= parity
    return [key]


def unmatched(count: int, mapping: IntArray) -> IntArray:
    """Indices in ``range(count)`` that ``mapping`` does not hit, ascending."""
    hit = np.zeros(count, dtype=bool)
    hit[mapping[mapping >= 0]] = True
    return np.flatnonzero(~hit).astype(np.int64)
