"""The three-way merge of a temporal surface slice by slice: models 2 and 3 (docs/merge.md, "Models 2 and 3").

Pure numpy over :mod:`tgsis.merge3`: no database. A model-2 surface (a
surface at instants) is a set of **instants** each holding a mesh; a model-3
surface (an evolving surface) a set of **topology periods**, each with its
nodes and triangles and the node positions at its **geometry instants**. A
slice is one mesh: an instant ``(times,)`` of model 2, a geometry instant
``(timem, timet)`` of model 3 (the period's nodes at their positions there,
the period's triangles).

The rules (the design note says why):

- an instant (a period) added or removed on one side only is taken; added
  on both sides alike, or removed on both, too;
- an instant (a period, a geometry instant) removed on one side and changed
  on the other, or added on both sides differently, is an **object-level
  conflict** (:class:`~tgsis.errors.InvalidInputError` naming it): there is
  no mesh to merge the other side's change into;
- model 3: a period whose topology (node ids, triangles) both sides changed,
  differently, is an object-level conflict;
- a slice the three states have that either side changed is merged by
  :func:`tgsis.merge3.three_way_merge` (a side's change alone is a region
  that merges by itself); its regions are numbered on through
  the object's slices (in the slices' order), so that one index names one
  region of the object;
- model 3: after the solutions, every geometry instant of a period must
  have the same nodes and triangles, else :class:`~tgsis.errors.PeriodTopologyError`
  (TG308, naming the period); when the slices no solution changes (taken
  from one side, merged by themselves) already disagree, no solution can
  merge the object: :func:`fixed_period_refusal` says so before any is chosen;
- the per-instant feature properties (the class's ``_pros`` rows) merge
  three ways column by column; a column both sides changed to other values
  is an object-level conflict.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from tgsis.errors import InvalidInputError, PeriodTopologyError
from tgsis.merge3 import MergeRegion, MeshMerge, MeshState, RegionDiscard, Solution, apply_solutions, three_way_merge

__all__ = [
    "SliceKey",
    "SliceRegion",
    "SlicedMerge",
    "SlicedState",
    "apply_sliced",
    "check_periods",
    "fixed_period_refusal",
    "merge_sliced",
    "same_state",
    "slice_text",
]

#: ``(times,)`` for model 2, ``(timem, timet)`` for model 3
SliceKey = tuple[float, ...]
#: the values of one per-instant feature property row, as text (None: NULL)
InstantRow = tuple[str | None, ...]
Kind = Literal["INSTANTS", "EVOLVING"]


@dataclass(frozen=True)
class SlicedState:
    """One state of a temporal surface: its slices' meshes and its per-instant feature property rows.

    Attributes
    ----------
    kind : {"INSTANTS", "EVOLVING"}
    slices : mapping of SliceKey to MeshState
        Keys ascending.
    instant_rows : mapping of SliceKey to tuple of str or None
        The per-instant feature property row of each instant that has one.
    name : str
        The object, as messages name it.
    instant_columns : tuple of str
        The names of the per-instant feature properties (the columns of ``instant_rows``).
    top_ids : mapping of SliceKey to (int, int)
        When the slices hold only the change and its one-ring (a read at the
        cost of the change): each slice's largest vertex and cell ids over the
        three whole states, :func:`tgsis.merge3.three_way_merge`'s ``top_ids``.
        Empty: the slices are whole.
    """

    kind: Kind
    slices: Mapping[SliceKey, MeshState]
    instant_rows: Mapping[SliceKey, InstantRow]
    name: str
    instant_columns: tuple[str, ...] = ()
    top_ids: Mapping[SliceKey, tuple[int, int]] = dataclasses.field(default_factory=dict)

    def periods(self) -> dict[float, list[SliceKey]]:
        """Model 3: each period's geometry instants (slice keys, ascending)."""
        out: dict[float, list[SliceKey]] = {}
        for key in sorted(self.slices):
            out.setdefault(key[0], []).append(key)
        return out


@dataclass(frozen=True)
class SliceRegion:
    """A region of one slice, numbered in the object: ``index`` is its number there, ``region`` the slice's own."""

    index: int
    key: SliceKey
    region: MergeRegion


@dataclass(frozen=True)
class SlicedMerge:
    """The three-way merge of a temporal surface (:func:`merge_sliced`).

    Attributes
    ----------
    base, parent, child : SlicedState
    merges : mapping of SliceKey to MeshMerge
        The slices both sides changed, merged by :func:`tgsis.merge3.three_way_merge`.
    taken : mapping of SliceKey to MeshState
        Every other slice of the result, as the side that changed it (or both) holds it.
    instant_rows : mapping of SliceKey to tuple
        The merged per-instant feature property rows.
    regions : tuple of SliceRegion
        The regions of the merged slices, numbered through the object.
    """

    base: SlicedState
    parent: SlicedState
    child: SlicedState
    merges: Mapping[SliceKey, MeshMerge]
    taken: Mapping[SliceKey, MeshState]
    instant_rows: Mapping[SliceKey, InstantRow]
    regions: tuple[SliceRegion, ...]

    @property
    def conflicts(self) -> tuple[SliceRegion, ...]:
        return tuple(r for r in self.regions if r.region.conflict)

    @property
    def merge_regions(self) -> tuple[MergeRegion, ...]:
        """The regions as :class:`MergeRegion`, each with its number in the object as ``index``."""
        return tuple(dataclasses.replace(r.region, index=r.index) for r in self.regions)

    def region(self, index: int) -> SliceRegion:
        for r in self.regions:
            if r.index == index:
                return r
        raise InvalidInputError(f"{self.base.name} has no region {index}")


def slice_text(kind: str, key: SliceKey) -> str:
    """How a message names a slice: ``instant 2.5``, ``geometry instant 3 of the period starting at 1``."""
    if kind == "EVOLVING":
        return f"geometry instant {key[1]!r} of the period starting at {key[0]!r}"
    return f"instant {key[0]!r}"


def _values_equal(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape:
        return False
    if a.dtype.kind == "f" or b.dtype.kind == "f":
        return bool(np.array_equal(a.astype(np.float64), b.astype(np.float64), equal_nan=True))
    return bool(np.array_equal(a, b))


def same_state(a: MeshState | None, b: MeshState | None) -> bool:
    """Whether two slices hold the same rows: ids, coordinates, cells, property values (NaN equal to NaN)."""
    if a is None or b is None:
        return a is b
    if not (
        np.array_equal(a.vertex_ids, b.vertex_ids)
        and np.array_equal(a.cell_ids, b.cell_ids)
        and np.array_equal(a.cells, b.cells)
        and _values_equal(a.vertices, b.vertices)
        and a.vertex_properties.keys() == b.vertex_properties.keys()
        and a.cell_properties.keys() == b.cell_properties.keys()
    ):
        return False
    return all(
        _values_equal(np.asarray(a.vertex_properties[n]), np.asarray(b.vertex_properties[n]))
        for n in a.vertex_properties
    ) and all(
        _values_equal(np.asarray(a.cell_properties[n]), np.asarray(b.cell_properties[n])) for n in a.cell_properties
    )


def _same_topology(a: MeshState | None, b: MeshState | None) -> bool:
    if a is None or b is None:
        return a is b
    return (
        np.array_equal(a.vertex_ids, b.vertex_ids)
        and np.array_equal(a.cell_ids, b.cell_ids)
        and np.array_equal(a.cells, b.cells)
    )


def _merge_rows(
    name: str, kind: str, base: SlicedState, parent: SlicedState, child: SlicedState
) -> dict[SliceKey, InstantRow]:
    """The per-instant feature property rows merged three ways, column by column."""
    rows: dict[SliceKey, InstantRow] = {}
    keys = set(base.instant_rows) | set(parent.instant_rows) | set(child.instant_rows)
    for key in sorted(keys):
        b, p, c = (s.instant_rows.get(key) for s in (base, parent, child))
        if p == c or c == b:
            chosen = p
        elif p == b:
            chosen = c
        elif p is None or c is None or b is None:
            raise InvalidInputError(
                f"{name}: the per-instant feature properties of {slice_text(kind, key)} were "
                f"{'removed' if p is None or c is None else 'added'} on one side and set otherwise on the other",
                hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
            )
        else:
            merged, both = [], []
            for i, (bv, pv, cv) in enumerate(zip(b, p, c, strict=True)):
                if pv == cv or cv == bv:
                    merged.append(pv)
                elif pv == bv:
                    merged.append(cv)
                else:
                    merged.append(pv)
                    both.append(i)
            if both:
                columns = base.instant_columns
                named = [columns[i] if i < len(columns) else f"column {i + 1}" for i in both]
                raise InvalidInputError(
                    f"{name}: per-instant feature properties ({', '.join(named)}) of "
                    f"{slice_text(kind, key)} were changed on both sides to other values",
                    hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
                )
            chosen = tuple(merged)
        if chosen is not None:
            rows[key] = chosen
    return rows


def _one_side(
    name: str, what: str, b: object, p: object, c: object, changed_p: bool, changed_c: bool
) -> Literal["parent", "child", "both"]:
    """Which side's slice (or period) to take when not merged within: refuses what only a person can decide."""
    if not changed_c:
        return "parent"
    if not changed_p:
        return "child"
    if b is not None and p is None and c is None:  # removed on both sides: taken (removed)
        return "both"
    if b is not None and (p is None or c is None):
        raise InvalidInputError(
            f"{name}: {what} was removed in the {'parent' if p is None else 'version'} and changed in the "
            f"{'version' if p is None else 'parent'}: a removal does not merge with a change",
            hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
        )
    return "both"


def merge_sliced(base: SlicedState, parent: SlicedState, child: SlicedState) -> SlicedMerge:
    """The three-way merge of a temporal surface, slice by slice (the module's rules).

    Raises
    ------
    InvalidInputError
        An object-level conflict: an instant or period removed on one side
        and changed on the other, added on both sides differently, a model-3
        period's topology changed on both sides differently, a per-instant
        feature property changed on both sides to other values. The message
        names the instant or period.
    """
    name, kind = base.name, base.kind
    merges: dict[SliceKey, MeshMerge] = {}
    taken: dict[SliceKey, MeshState] = {}
    states = (base, parent, child)
    tops: dict[SliceKey, tuple[int, int]] = {}
    for state in states:
        for key, (top_v, top_c) in state.top_ids.items():
            old = tops.get(key, (-1, -1))
            tops[key] = (max(old[0], int(top_v)), max(old[1], int(top_c)))
    if kind == "EVOLVING":
        by = dict(zip(("base", "parent", "child"), states, strict=True))
        periods = {s: state.periods() for s, state in by.items()}
        starts = sorted(set().union(*(p.keys() for p in periods.values())))
        for m in starts:
            keys = {s: periods[s].get(m, []) for s in by}
            slices = {s: {k: by[s].slices[k] for k in keys[s]} for s in by}
            b, p, c = (slices[s] or None for s in ("base", "parent", "child"))
            what = f"the topology period starting at {m!r}"
            changed_p = not _same_period(b, p)
            changed_c = not _same_period(b, c)
            side = _one_side(name, what, b, p, c, changed_p, changed_c)
            if side != "both" and (b is None or p is None or c is None):  # added or removed on one side
                taken.update((slices["parent"] if side == "parent" else slices["child"]) or {})
                continue
            if b is None or p is None or c is None:  # added on both sides: alike, or a conflict
                if _same_period(p, c):
                    taken.update(p or {})
                    continue
                raise InvalidInputError(
                    f"{name}: {what} was added on both sides, differently",
                    hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
                )
            topo = {s: next(iter(slices[s].values())) for s in by}
            if (
                not _same_topology(topo["base"], topo["parent"])
                and not _same_topology(topo["base"], topo["child"])
                and not _same_topology(topo["parent"], topo["child"])
            ):
                raise InvalidInputError(
                    f"{name}: the topology (nodes, triangles) of {what} was changed on both sides, differently: "
                    "topology periods changed on both sides do not merge by region",
                    hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
                )
            _merge_keys(name, kind, slices["base"], slices["parent"], slices["child"], merges, taken, tops)
    else:
        _merge_keys(name, kind, dict(base.slices), dict(parent.slices), dict(child.slices), merges, taken, tops)
    rows = _merge_rows(name, kind, base, parent, child)
    regions: list[SliceRegion] = []
    for key in sorted(merges):
        for r in merges[key].regions:
            regions.append(SliceRegion(len(regions), key, r))
    return SlicedMerge(base, parent, child, merges, taken, rows, tuple(regions))


def _same_period(a: Mapping[SliceKey, MeshState] | None, b: Mapping[SliceKey, MeshState] | None) -> bool:
    if not a or not b:
        return not a and not b
    return a.keys() == b.keys() and all(same_state(a[k], b[k]) for k in a)


def _merge_keys(
    name: str,
    kind: str,
    base: Mapping[SliceKey, MeshState],
    parent: Mapping[SliceKey, MeshState],
    child: Mapping[SliceKey, MeshState],
    merges: dict[SliceKey, MeshMerge],
    taken: dict[SliceKey, MeshState],
    top_ids: Mapping[SliceKey, tuple[int, int]],
) -> None:
    """Slice by slice: taken from the side that changed it, or merged three ways when both did.

    ``top_ids``: per slice, the largest ids of the whole states when the slices are restricted to the change.
    """
    for key in sorted(set(base) | set(parent) | set(child)):
        b, p, c = base.get(key), parent.get(key), child.get(key)
        what = slice_text(kind, key)
        side = _one_side(name, what, b, p, c, not same_state(b, p), not same_state(b, c))
        if b is not None and p is not None and c is not None and (side == "both" or not same_state(p, c)):
            # changed on one side or both: merged, so that its regions say what each side changed
            merges[key] = three_way_merge(
                dataclasses.replace(b, name=f"{name}, {what}"),
                dataclasses.replace(p, name=f"{name}, {what}"),
                dataclasses.replace(c, name=f"{name}, {what}"),
                top_ids=top_ids.get(key),
            )
            continue
        if side == "parent" or side == "child":
            chosen = p if side == "parent" else c
            if chosen is not None:
                taken[key] = chosen
            continue
        if same_state(p, c):
            if p is not None:
                taken[key] = p
            continue
        raise InvalidInputError(
            f"{name}: {what} was added on both sides, differently",
            hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
        )


def apply_sliced(
    merge: SlicedMerge, solutions: Mapping[int, Solution], *, names: Mapping[int, str] | None = None
) -> tuple[dict[SliceKey, MeshState], tuple[RegionDiscard, ...]]:
    """The merged slices with ``solutions`` (by the object's region numbers), and what they discard.

    Each merged slice takes :func:`tgsis.merge3.apply_solutions` with its
    regions' solutions; the discards name the object's region numbers.

    Raises
    ------
    InvalidInputError
        A solution for a region that is no conflict, or a conflict without one.
    InvalidMergeError
        A slice's result is no valid mesh.
    PeriodTopologyError
        Model 3: the merged geometry instants of one period have other nodes or triangles.
    """
    known = {r.index for r in merge.regions}
    unknown = sorted(set(solutions) - known)
    if unknown:
        raise InvalidInputError(f"{merge.base.name} has no region {unknown[0]}")
    result: dict[SliceKey, MeshState] = dict(merge.taken)
    discards: list[RegionDiscard] = []
    by_key: dict[SliceKey, list[SliceRegion]] = {}
    for r in merge.regions:
        by_key.setdefault(r.key, []).append(r)
    for key, mm in merge.merges.items():
        mine = by_key.get(key, [])
        local = {r.region.index: solutions[r.index] for r in mine if r.index in solutions}
        local_names = {r.region.index: names[r.index] for r in mine if names and r.index in names}
        if not local and mm.merged is not None:
            result[key] = mm.merged.state
            continue
        resolved = apply_solutions(mm, local, names=local_names)
        number = {r.region.index: r.index for r in mine}
        discards += [dataclasses.replace(d, region=number[d.region]) for d in resolved.discards]
        result[key] = resolved.state
    merged = dict(sorted(result.items()))
    if merge.base.kind == "EVOLVING":
        check_periods(merge.base.name, merged)
    return merged, tuple(discards)


def check_periods(name: str, slices: Mapping[SliceKey, MeshState]) -> None:
    """Refuse (TG308) model-3 slices whose geometry instants of one period have other nodes or triangles."""
    first: dict[float, tuple[SliceKey, MeshState]] = {}
    for key, state in sorted(slices.items()):
        seen = first.setdefault(key[0], (key, state))
        if seen[1] is not state and not _same_topology(seen[1], state):
            raise PeriodTopologyError(
                f"{name}: merged instant by instant, the topology period starting at {key[0]!r} would have other "
                f"nodes or triangles at its geometry instant {key[1]!r} than at {seen[0][1]!r}: a period has one "
                "topology",
                hint="tgsis.resolve_conflict solves it as a whole object (parent, child or manual)",
            )


def fixed_period_refusal(merge: SlicedMerge) -> str | None:
    """Model 3: the TG308 refusal every merge of ``merge`` would meet whatever the solutions (its text), or None.

    The slices no solution changes — taken from one side, or merged without a
    conflicting region — must already give each topology period one
    topology; when they do not (a geometry instant added on one side with the
    period's old topology, the period's triangles changed on the other), no
    choice of solutions merges the object: it is an object-level conflict
    (``tgsis.find_conflicts`` says so before the merge). Slices with a
    conflicting region are left out: their topology hangs on the solutions,
    and :func:`apply_sliced` checks it once they are chosen.
    """
    if merge.base.kind != "EVOLVING":
        return None
    conflicting = {r.key for r in merge.conflicts}
    fixed = dict(merge.taken)
    for key, mm in merge.merges.items():
        if key not in conflicting and mm.merged is not None:
            fixed[key] = mm.merged.state
    try:
        check_periods(merge.base.name, fixed)
    except PeriodTopologyError as exc:
        return f"{exc.message} (the merge refuses it: {exc.code}); {exc.hint}"
    return None
