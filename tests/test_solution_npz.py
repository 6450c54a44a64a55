"""A region solution's stored mesh (``tgsis.conflict_regions.solution_mesh``, .npz bytes) read back safely.

Any role that may resolve a conflict can store those bytes with SQL
``tgsis.resolve_region``; the merge, run later by a more privileged role,
reads them. So a forged file must be refused as bad input, quickly and
without memory to match its claims: no pickles, no deflated member that
expands a few bytes into gigabytes, no array header declaring more values
than the member holds.
"""

from __future__ import annotations

import io
import zipfile

import numpy as np
import pytest

import tgsis
from tgsis.db.regions import state_from_npz, state_to_npz
from tgsis.merge3 import MeshState


def _state() -> MeshState:
    vertices = np.array([[0.0, 0.0, 1.5], [1.0, 0.0, -2.25], [0.0, 1.0, 3.0]])
    return MeshState(
        3,
        np.array([4, 7, 9]),
        vertices,
        np.array([2]),
        np.array([[4, 7, 9]]),
        {"porosity": np.array([0.1, 0.2, 0.3])},
        {"facies": np.array([5])},
        "fault",
    )


def _members(data: bytes) -> dict[str, bytes]:
    with zipfile.ZipFile(io.BytesIO(data)) as z:
        return {name: z.read(name) for name in z.namelist()}


def _zip(members: dict[str, bytes], deflated: tuple[str, ...] = ()) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w") as z:
        for name, payload in members.items():
            z.writestr(name, payload, compress_type=zipfile.ZIP_DEFLATED if name in deflated else zipfile.ZIP_STORED)
    return out.getvalue()


def test_a_state_round_trips_bit_for_bit() -> None:
    state = _state()
    back = state_from_npz(state_to_npz(state), "fault")
    assert back.vertices.tobytes() == state.vertices.tobytes()
    assert back.vertex_ids.tolist() == [4, 7, 9] and back.cells.tolist() == [[4, 7, 9]]
    assert back.vertex_properties["porosity"].tobytes() == state.vertex_properties["porosity"].tobytes()
    assert back.cell_properties["facies"].tolist() == [5]


def test_a_deflated_member_is_refused_before_it_expands() -> None:
    # 200 MB of zeros deflate to ~200 kB: the merge would have inflated it into memory
    members = _members(state_to_npz(_state()))
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (25_000_000,)})
    members["vertex:bomb.npy"] = header.getvalue() + bytes(200_000_000)
    forged = _zip(members, deflated=("vertex:bomb.npy",))
    assert len(forged) < 1_000_000
    with pytest.raises(tgsis.InvalidInputError, match=r"vertex:bomb\.npy.*compressed"):
        state_from_npz(forged, "fault")


def test_a_header_claiming_more_values_than_it_holds_is_refused() -> None:
    members = _members(state_to_npz(_state()))
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(
        header, {"descr": "<f8", "fortran_order": False, "shape": (10**12, 3)}
    )  # 24 TB declared, 24 bytes held
    members["vertices.npy"] = header.getvalue() + bytes(24)
    with pytest.raises(tgsis.InvalidInputError, match=r"vertices\.npy.*declares"):
        state_from_npz(_zip(members), "fault")


@pytest.mark.parametrize(
    "forge",
    [
        lambda m: {**m, "vertices.npy": b"not an array"},
        lambda m: {k: v for k, v in m.items() if k != "cells.npy"},
        lambda m: {**m, "cell_size.npy": m["vertices.npy"]},
    ],
    ids=["not-npy", "member-missing", "cell-size-not-a-number"],
)
def test_other_forged_files_are_bad_input(forge: object) -> None:
    members = _members(state_to_npz(_state()))
    with pytest.raises(tgsis.InvalidInputError, match="fault: the stored mesh of a solution"):
        state_from_npz(_zip(forge(members)), "fault")  # type: ignore[operator]


def test_a_pickled_member_is_refused() -> None:
    members = _members(state_to_npz(_state()))
    out = io.BytesIO()
    np.save(out, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    members["vertex:evil.npy"] = out.getvalue()
    with pytest.raises(tgsis.InvalidInputError, match="vertex:evil"):
        state_from_npz(_zip(members), "fault")
