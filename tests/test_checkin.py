"""Saving an edited mesh by difference, and check-out / check-in without lost updates."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tgsis.db import features as F

Conn = psycopg.Connection[Any]


def _grid(side: int, seed: int = 0) -> tgsis.Surface:
    """A bumpy grid surface with a vertex property (side² vertices, 2 (side-1)² triangles)."""
    rng = np.random.default_rng(seed)
    u, v = np.meshgrid(np.arange(side, dtype=float), np.arange(side, dtype=float))
    vertices = np.stack([u.ravel(), v.ravel(), rng.random(side * side)], axis=1)
    idx = np.arange(side * side).reshape(side, side)
    a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
    return tgsis.Surface(
        vertices,
        np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)]),
        vertex_properties={"porosity": rng.random(side * side)},
        name="grid",
    )


def _edit(mesh: tgsis.Surface, fraction: float, seed: int = 1) -> tgsis.Surface:
    """Move a fraction of the vertices up, flip a few diagonals, change a few porosities, shuffle everything."""
    rng = np.random.default_rng(seed)
    vertices, cells = mesh.vertices.copy(), mesh.cells.copy()
    porosity = mesh.vertex_properties["porosity"].copy()
    moved = rng.choice(len(vertices), int(fraction * len(vertices)), replace=False)
    vertices[moved, 2] += 10.0
    porosity[rng.choice(len(vertices), 5, replace=False)] = -1.0
    # flip the diagonal of a few quads: (a, b, d) + (a, d, c) -> (a, b, c) + (b, d, c)
    half = len(cells) // 2
    for q in rng.choice(half, 3, replace=False):
        a, b, d = cells[q]
        c = cells[half + q][2]
        cells[q], cells[half + q] = (a, b, c), (b, d, c)
    vperm, cperm = rng.permutation(len(vertices)), rng.permutation(len(cells))
    rank = np.empty_like(vperm)
    rank[vperm] = np.arange(len(vperm))
    return tgsis.Surface(
        vertices[vperm], rank[cells[cperm]], vertex_properties={"porosity": porosity[vperm]}, name=mesh.name
    )


def _same_surface(a: tgsis.Mesh, b: tgsis.Mesh) -> bool:
    """Same vertices, oriented cells and vertex properties, whatever the order."""
    diff = tgsis.compare_meshes(a, b)
    if not diff.identical:
        return False
    return all(
        np.array_equal(a.vertex_properties[k][diff.vertex_map], b.vertex_properties[k]) for k in a.vertex_properties
    )


@pytest.fixture
def horizons(conn: Conn) -> F.FeatureClass:
    fc = F.create_feature_class(
        conn, "horizons", "SURFACE", feature_properties={"creator": "text"}, cell_properties={"porosity": "float8"}
    )
    conn.commit()
    return fc


def _rows(conn: Conn, geoid: int) -> dict[str, dict[int, tuple[Any, ...]]]:
    return {
        "vrtx": {
            r[0]: r[1:] for r in conn.execute("SELECT vrtxid, x, y, z FROM tgsis.vrtx WHERE geoid = %s", (geoid,))
        },
        "trgl": {
            r[0]: r[1:]
            for r in conn.execute("SELECT trglid, vrtxid1, vrtxid2, vrtxid3 FROM tgsis.trgl WHERE geoid = %s", (geoid,))
        },
        "cellpros": {
            r[0]: r[1:]
            for r in conn.execute("SELECT _idx, porosity FROM horizons_cellpros WHERE _geoid = %s", (geoid,))
        },
    }


# --------------------------------------------------------------------------- save by difference


def test_save_writes_only_the_difference_and_keeps_ids(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(60)
    fid = F.insert_feature(conn, horizons, base, {"creator": "ann"})
    conn.commit()
    before = _rows(conn, fid)
    edited = _edit(base, 0.01)
    result = tgsis.save_feature(conn, horizons, fid, edited)
    conn.commit()
    after = _rows(conn, fid)
    diff = result.diff
    # by the comparison's definitions 36 vertices went and 36 came; they are the same vertices moved
    assert diff.counts()["vertices_removed"] == diff.counts()["vertices_added"] == 36
    assert result.vertices_moved == 36
    # every vertex kept its id (the moved ones with new coordinates), every triangle but the 6 flipped ones too
    assert set(after["vrtx"]) == set(before["vrtx"])
    assert sum(before["vrtx"][i] != after["vrtx"][i] for i in before["vrtx"]) == 36
    kept_t = set(before["trgl"]) & set(after["trgl"])
    assert len(kept_t) == len(before["trgl"]) - 6 and len(after["trgl"]) == len(before["trgl"])
    assert all(before["trgl"][i] == after["trgl"][i] for i in kept_t)
    assert min(set(after["trgl"]) - kept_t) == max(before["trgl"]) + 1  # new ids above every old one
    # rows written are proportional to the edit: 36 moved vertices, 6 triangles, 5 properties, the geometry row
    assert result.rows_written == 2 * 36 + 2 * 6 + 2 * 5 + 1
    mesh_rows = len(base.vertices) * 2 + len(base.cells)
    assert result.rows_written <= 0.01 * mesh_rows
    assert result.property_rows_changed == 5
    # what is stored now is the edited mesh
    stored = F.fetch_feature(conn, horizons, fid)
    assert _same_surface(stored.mesh, edited)  # type: ignore[arg-type]
    assert stored.properties == {"creator": "ann"}
    assert conn.execute("SELECT count(*) FROM tgsis.check_geometry(%s)", (fid,)).fetchone() == (0,)
    row = conn.execute(
        "SELECT nvrtx, ncell, bbox = cube(ARRAY[0, 0, %s]::float8[], ARRAY[59, 59, %s]::float8[]) "
        "FROM tgsis.geometry WHERE geoid = %s",
        (float(edited.vertices[:, 2].min()), float(edited.vertices[:, 2].max()), fid),
    ).fetchone()
    assert row == (edited.n_vertices, edited.n_cells, True)


def test_saving_the_same_mesh_writes_nothing(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(20)
    fid = F.insert_feature(conn, horizons, base)
    conn.commit()
    shuffled = _edit(base, 0.0, seed=3)  # no vertex moves, but 3 diagonals flip and 5 porosities change
    plain = tgsis.Surface(
        base.vertices[::-1],
        (len(base.vertices) - 1 - base.cells)[::-1],
        vertex_properties={"porosity": base.vertex_properties["porosity"][::-1]},
        name="grid",
    )
    result = tgsis.save_feature(conn, horizons, fid, plain)
    assert result.rows_written == 0 and result.diff.identical
    result = tgsis.save_feature(conn, horizons, fid, shuffled)
    assert result.diff.counts()["cells_removed"] == 6 and result.rows_written > 0


def test_cell_aligned_properties_follow_their_cells(conn: Conn) -> None:
    fc = F.create_feature_class(conn, "blocks", "SURFACE", cell_properties={"facies": "int4"}, alignment="CELL")
    base = _grid(10)
    base = tgsis.Surface(base.vertices, base.cells, cell_properties={"facies": np.arange(base.n_cells)})
    fid = F.insert_feature(conn, fc, base)
    conn.commit()
    facies = np.arange(base.n_cells)
    facies[7] = 1000  # a value change on a kept triangle
    vertices = base.vertices.copy()
    vertices[55, 2] = 5.0  # its 6 triangles become new ones
    edited = tgsis.Surface(vertices, base.cells, cell_properties={"facies": facies})
    result = tgsis.save_feature(conn, fc, fid, edited)
    conn.commit()
    assert result.property_rows_changed == (0 if 7 in np.flatnonzero((base.cells == 55).any(axis=1)) else 1)
    stored = F.fetch_feature(conn, fc, fid).mesh
    diff = tgsis.compare_meshes(stored, edited)  # type: ignore[arg-type]
    assert diff.identical
    assert np.array_equal(stored.cell_properties["facies"][diff.cell_map], facies)  # type: ignore[union-attr]


def test_save_in_a_child_version_stores_only_new_row_versions(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(100)
    fid = F.insert_feature(conn, horizons, base)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "edit")
    conn.commit()

    def storage_rows() -> int:
        """Row versions (or chunk versions, once stored in chunks) in the storage of the feature's tables."""
        return sum(
            int(conn.execute(f"SELECT count(*) FROM {t}").fetchall()[0][0])
            for t in (
                str((conn.execute("SELECT tgsis.storage_table(%s, %s)", t).fetchone() or ("",))[0])
                for t in (
                    ("tgsis", "vrtx"),
                    ("tgsis", "trgl"),
                    (horizons.schema, "horizons_cellpros"),
                    ("tgsis", "geometry"),
                )
            )
        )

    before = storage_rows()
    edited = _edit(base, 0.01)
    with tgsis.in_version(conn, "edit"):
        result = tgsis.save_feature(conn, horizons, fid, edited)
        conn.commit()
        assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, edited)  # type: ignore[arg-type]
    added = storage_rows() - before
    assert 0 < added <= result.rows_inserted + result.rows_updated
    assert added <= 0.03 * (2 * base.n_vertices + base.n_cells)
    # DEFAULT still has the old surface; the merge brings the edit
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, base)  # type: ignore[arg-type]
    tgsis.merge_version(conn, "edit")
    conn.commit()
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, edited)  # type: ignore[arg-type]


def test_save_is_refused_on_an_object_locked_by_another_version(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(8)
    fid = F.insert_feature(conn, horizons, base)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "holder")
    tgsis.lock_objects(conn, "holder", "feature", [str(fid)])
    conn.commit()
    vertices = base.vertices.copy()
    vertices[0, 2] = 99.0
    with pytest.raises(tgsis.ObjectLockedError):
        tgsis.save_feature(
            conn, horizons, fid, tgsis.Surface(vertices, base.cells, vertex_properties=base.vertex_properties)
        )
    # adding a vertex only (no row deleted) is refused as well
    grown = tgsis.Surface(
        np.r_[base.vertices, [[100.0, 100.0, 0.0]]],
        base.cells,
        vertex_properties={"porosity": np.r_[base.vertex_properties["porosity"], 0.0]},
    )
    with pytest.raises(tgsis.ObjectLockedError):
        tgsis.save_feature(conn, horizons, fid, grown)
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, base)  # type: ignore[arg-type]


# --------------------------------------------------------------------------- check-out / check-in


def test_checkout_edit_checkin(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(30)
    fid = F.insert_feature(conn, horizons, base, {"creator": "ann"})
    conn.commit()
    co = tgsis.checkout(conn, fid)
    assert co.token.feature_id == fid and co.token.feature_class == "horizons" and co.token.version == "DEFAULT"
    assert co.properties == {"creator": "ann"}
    assert _same_surface(co.mesh, base)
    edited = _edit(co.mesh, 0.02)  # type: ignore[arg-type]
    result = tgsis.checkin(conn, co, edited, {"creator": "bob"}, keep=True)
    conn.commit()
    assert not result.conflict and result.version == "DEFAULT"
    stored = F.fetch_feature(conn, horizons, fid)
    assert _same_surface(stored.mesh, edited) and stored.properties == {"creator": "bob"}  # type: ignore[arg-type]
    # the same token again is a conflict with oneself: the object is no longer what it was checked out as
    with pytest.raises(tgsis.CheckoutConflictError, match=f"feature {fid} was changed in version 'DEFAULT'"):
        tgsis.checkin(conn, co, base)
    # the kept check-out goes on from the new state
    assert result.checkout is not None
    again = _edit(result.checkout.mesh, 0.01, seed=9)  # type: ignore[arg-type]
    tgsis.checkin(conn, result.checkout, again)
    conn.commit()
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, again)  # type: ignore[arg-type]


def _fingerprint(conn: Conn, fid: int) -> str:
    return str(conn.execute("SELECT tgsis.object_fingerprint(%s)", (fid,)).fetchone()[0])  # type: ignore[index]


def test_two_clients_no_lost_update(db_dsn: str, horizons: F.FeatureClass) -> None:
    """Ann and Bob check out the same surface and both edit it: Bob's later check-in is refused, then redone."""
    with psycopg.connect(db_dsn) as ann, psycopg.connect(db_dsn) as bob:
        base = _grid(25)
        fid = F.insert_feature(ann, horizons, base)
        ann.commit()
        ann_co, bob_co = tgsis.checkout(ann, fid), tgsis.checkout(bob, fid)
        ann_mesh, bob_mesh = ann_co.mesh.copy(), bob_co.mesh.copy()
        ann_mesh.vertices[0, 2] = 100.0  # different vertices: each edit alone is fine
        bob_mesh.vertices[600, 2] = -100.0
        tgsis.checkin(ann, ann_co, ann_mesh)
        ann.commit()
        state = _fingerprint(bob, fid)
        with pytest.raises(tgsis.CheckoutConflictError) as refused:
            tgsis.checkin(bob, bob_co, bob_mesh)
        assert refused.value.sqlstate == "TG304" and str(fid) in str(refused.value)
        bob.rollback()
        assert _fingerprint(bob, fid) == state  # nothing of Bob's was written
        # Bob checks out again (seeing Ann's edit), redoes his, checks in: both edits are there
        bob_co = tgsis.checkout(bob, fid)
        redo = bob_co.mesh.copy()
        redo.vertices[np.flatnonzero((redo.vertices[:, :2] == base.vertices[600, :2]).all(axis=1)), 2] = -100.0
        tgsis.checkin(bob, bob_co, redo)
        bob.commit()
        final = F.fetch_feature(ann, horizons, fid).mesh
        z = {tuple(v[:2]): v[2] for v in final.vertices}  # type: ignore[union-attr]
        assert z[tuple(base.vertices[0, :2])] == 100.0 and z[tuple(base.vertices[600, :2])] == -100.0


def test_simultaneous_checkins_one_wins(db_dsn: str, horizons: F.FeatureClass) -> None:
    """Two check-ins from the same base at the same moment: the lock lets exactly one through."""
    with psycopg.connect(db_dsn) as setup:
        base = _grid(40)
        fid = F.insert_feature(setup, horizons, base)
        setup.commit()
        co = tgsis.checkout(setup, fid)
    outcomes: list[str] = []
    barrier = threading.Barrier(2)

    def client(z: float) -> None:
        with psycopg.connect(db_dsn) as c:
            mesh = co.mesh.copy()
            mesh.vertices[:10, 2] = z
            barrier.wait()
            try:
                tgsis.checkin(c, co, mesh)
                c.commit()
                outcomes.append(f"ok {z}")
            except tgsis.CheckoutConflictError:
                outcomes.append("conflict")

    threads = [threading.Thread(target=client, args=(z,)) for z in (7.0, 8.0)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(o.split()[0] for o in outcomes) == ["conflict", "ok"]
    winner = float(next(o for o in outcomes if o.startswith("ok")).split()[1])
    with psycopg.connect(db_dsn) as c:
        stored = F.fetch_feature(c, horizons, fid).mesh
        assert np.all(stored.vertices[:10, 2] == winner)  # type: ignore[union-attr]


def test_conflict_goes_into_a_child_version(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(20)
    fid = F.insert_feature(conn, horizons, base)
    tgsis.enable_feature_versioning(conn)
    conn.commit()
    co = tgsis.checkout(conn, fid)
    theirs = base.vertices.copy()
    theirs[5, 2] = 50.0
    tgsis.save_feature(conn, horizons, fid, tgsis.Surface(theirs, base.cells, vertex_properties=base.vertex_properties))
    conn.commit()
    mine = co.mesh.copy()
    mine.vertices[300, 2] = -50.0
    result = tgsis.checkin(conn, co, mine, on_conflict="child")
    conn.commit()
    assert result.conflict and result.version == f"checkin_{fid}"
    assert tgsis.working_version(conn) == "DEFAULT"
    # nothing is lost: DEFAULT has their edit, the child has mine
    assert F.fetch_feature(conn, horizons, fid).mesh.vertices[5, 2] == 50.0  # type: ignore[union-attr]
    with tgsis.in_version(conn, result.version):
        assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, mine)  # type: ignore[arg-type]
    # a second conflicting check-in gets its own child
    again = tgsis.checkin(conn, co, mine, on_conflict="child")
    conn.commit()
    assert again.version == f"checkin_{fid}_2"


def test_conflict_child_needs_versioning(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _grid(6))
    conn.commit()
    co = tgsis.checkout(conn, fid)
    tgsis.save_feature(conn, horizons, fid, _edit(co.mesh, 0.1))  # type: ignore[arg-type]
    conn.commit()
    state = _fingerprint(conn, fid)
    with pytest.raises(tgsis.CheckoutConflictError, match="feature versioning is off"):
        tgsis.checkin(conn, co, co.mesh, on_conflict="child")
    conn.rollback()
    assert _fingerprint(conn, fid) == state


def test_checkin_of_a_deleted_feature(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _grid(6))
    conn.commit()
    co = tgsis.checkout(conn, fid)
    F.delete_feature(conn, horizons, fid)
    conn.commit()
    with pytest.raises(tgsis.CheckoutConflictError, match=f"feature {fid} was deleted"):
        tgsis.checkin(conn, co)


def test_checkout_in_a_version_checks_in_there(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(12)
    fid = F.insert_feature(conn, horizons, base)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "mine")
    conn.commit()
    with tgsis.in_version(conn, "mine"):
        co = tgsis.checkout(conn, fid)
    assert co.token.version == "mine"
    edited = _edit(co.mesh, 0.05)  # type: ignore[arg-type]
    assert tgsis.checkin(conn, co, edited).version == "mine"  # the session is in DEFAULT
    conn.commit()
    assert tgsis.working_version(conn) == "DEFAULT"
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, base)  # type: ignore[arg-type]
    with tgsis.in_version(conn, "mine"):
        assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, edited)  # type: ignore[arg-type]


def test_checkout_file_round_trip(conn: Conn, horizons: F.FeatureClass, tmp_path: Path) -> None:
    fid = F.insert_feature(conn, horizons, _grid(9), {"creator": "ann"})
    conn.commit()
    co = tgsis.checkout(conn, fid)
    loaded = tgsis.Checkout.load(co.save(tmp_path / "co.npz"))
    assert loaded.token == co.token and loaded.properties == co.properties
    assert loaded.base.mesh.same_as(co.base.mesh)
    assert np.array_equal(loaded.base.vertex_ids, co.base.vertex_ids)
    assert np.array_equal(loaded.base.cell_ids, co.base.cell_ids)
    edited = _edit(loaded.mesh, 0.1)  # type: ignore[arg-type]
    tgsis.checkin(conn, loaded, edited)
    conn.commit()
    assert _same_surface(F.fetch_feature(conn, horizons, fid).mesh, edited)  # type: ignore[arg-type]
    (tmp_path / "bad.npz").write_bytes(b"not a zip")
    with pytest.raises(tgsis.FileFormatError):
        tgsis.Checkout.load(tmp_path / "bad.npz")


def test_bad_saves_and_checkins_change_nothing(conn: Conn, horizons: F.FeatureClass) -> None:
    base = _grid(7)
    fid = F.insert_feature(conn, horizons, base)
    evolving = F.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING")
    F.create_feature_class(conn, "groups", "GEOMETRYCOLLECTION")
    conn.commit()
    co = tgsis.checkout(conn, fid)
    state = _fingerprint(conn, fid)
    no_props = tgsis.Surface(base.vertices, base.cells)
    lines = tgsis.LineSet(base.vertices, [[0, 1]], vertex_properties=base.vertex_properties)
    bad_calls: list[tuple[Callable[[], object], type[Exception], str]] = [
        (lambda: tgsis.save_feature(conn, horizons, fid, no_props), tgsis.InvalidPropertyError, "porosity"),
        (lambda: tgsis.save_feature(conn, horizons, fid, lines), tgsis.InvalidGeometryError, "LineSet"),
        (lambda: tgsis.save_feature(conn, horizons, fid + 1000, base), tgsis.NotFoundError, str(fid + 1000)),
        (lambda: tgsis.save_feature(conn, horizons, fid, base, {"nope": 1}), tgsis.InvalidPropertyError, "nope"),
        (lambda: tgsis.save_feature(conn, evolving, fid, base), tgsis.InvalidInputError, "temporal"),
        (lambda: tgsis.save_feature(conn, "groups", fid, base), tgsis.InvalidInputError, "GEOMETRYCOLLECTION"),
        (lambda: tgsis.save_feature(conn, horizons, fid, base, tolerance=-1.0), tgsis.InvalidInputError, "tolerance"),
        (lambda: tgsis.save_feature(conn, horizons, fid, "mesh"), tgsis.InvalidGeometryError, "str"),  # type: ignore[arg-type]
        (lambda: tgsis.checkin(conn, co, no_props), tgsis.InvalidPropertyError, "porosity"),
        (lambda: tgsis.checkin(conn, co, base, on_conflict="nope"), tgsis.InvalidInputError, "on_conflict"),  # type: ignore[arg-type]
        (lambda: tgsis.checkout(conn, fid + 1000), tgsis.NotFoundError, str(fid + 1000)),
    ]
    for call, error, text in bad_calls:
        with pytest.raises(error, match=text):
            call()
        conn.rollback()
        assert _fingerprint(conn, fid) == state
    # a token from another database
    other = tgsis.Checkout(tgsis.CheckoutToken(**{**co.token.__dict__, "database": "elsewhere"}), co.base)
    with pytest.raises(tgsis.InvalidInputError, match="elsewhere"):
        tgsis.checkin(conn, other, base)
    conn.rollback()
    # a snapshot that would not see a concurrent check-in's commit
    with conn.transaction():
        conn.execute("SET TRANSACTION ISOLATION LEVEL REPEATABLE READ")
        with pytest.raises(tgsis.InvalidInputError, match="repeatable read"):
            tgsis.checkin(conn, co, base)
    conn.rollback()
    # after all that, the token is still good
    tgsis.checkin(conn, co, _edit(co.mesh, 0.1))  # type: ignore[arg-type]
    conn.commit()
    assert _fingerprint(conn, fid) != state


def test_fingerprint_sees_every_kind_of_change(conn: Conn, horizons: F.FeatureClass) -> None:
    fid = F.insert_feature(conn, horizons, _grid(5), {"creator": "ann"})
    conn.commit()
    seen = {_fingerprint(conn, fid)}
    changes = [
        "UPDATE tgsis.vrtx SET z = z + 1e-12 WHERE geoid = {g} AND vrtxid = 3",
        # two vertices swap their y: same multiset of column values, different rows
        "UPDATE tgsis.vrtx SET y = CASE vrtxid WHEN 0 THEN 1 ELSE 0 END WHERE geoid = {g} AND vrtxid IN (0, 5)",
        "DELETE FROM tgsis.trgl WHERE geoid = {g} AND trglid = 0",
        "UPDATE horizons_cellpros SET porosity = 2 WHERE _geoid = {g} AND _idx = 1",
        "UPDATE horizons SET creator = 'bob' WHERE _geoid = {g}",
        "UPDATE tgsis.geometry SET geoname = 'renamed' WHERE geoid = {g}",
        "INSERT INTO tgsis.vrtx VALUES ({g}, 99, 0, 0, 0)",
        # a row renumbered (the id is not hashed itself: it seeds the hashes of the other columns)
        "UPDATE tgsis.trgl SET trglid = 1000 WHERE geoid = {g} AND trglid = 5",
        "UPDATE horizons_cellpros SET _idx = 1000 WHERE _geoid = {g} AND _idx = 2",
    ]
    for change in changes:
        conn.execute(change.format(g=fid))
        now = _fingerprint(conn, fid)
        assert now not in seen, change
        seen.add(now)


# --------------------------------------------------------------------------- real data: two releases of the CFM


def test_cfm_releases_checked_in_over_each_other(conn: Conn) -> None:
    """CFM 6.1 checked in over 5.3: the re-exported Garlock fault writes almost nothing with a tolerance,
    the re-interpreted Oceanic fault is rewritten, exactly."""
    from tests.shared_data import cfm
    from tgsis import formats

    fc = F.create_feature_class(conn, "faults", "SURFACE")
    conn.commit()
    for name, tolerance, expect_small in (
        ("GRFS-GRFZ-WEST-Garlock_fault-CFM5_1000m.ts", 1e-2, True),
        ("CRFA-OCNZ-MULT-Oceanic_fault-CFM5_1000m.ts", 0.0, False),
    ):
        old, new = formats.read_one(cfm(f"cfm5.3/{name}")), formats.read_one(cfm(f"cfm6.1/{name}"))
        fid = F.insert_feature(conn, fc, old)
        conn.commit()
        co = tgsis.checkout(conn, fid)
        result = tgsis.checkin(conn, co, new, tolerance=tolerance)
        conn.commit()
        stored = F.fetch_feature(conn, fc, fid).mesh
        assert isinstance(stored, tgsis.Surface)
        rows = 2 * old.n_vertices + old.n_cells  # vertices, triangles, and the mesh's own count again for scale
        if expect_small:
            # every vertex within 1 cm keeps its stored (5.3) coordinates; only 4 triangles differ
            assert result.save.diff.counts()["vertices_kept"] == new.n_vertices
            assert result.save.rows_written <= 10 and result.save.rows_written < 0.01 * rows
            diff = tgsis.compare_meshes(new, stored, tolerance=tolerance)
            assert diff.identical
            assert np.abs(stored.vertices - new.vertices[diff.vertex_map]).max() <= tolerance
        else:
            assert _same_surface(stored, new)
            assert result.save.rows_written > new.n_vertices


def test_checkout_in_a_child_goes_through_the_normal_conflict_path(conn: Conn, horizons: F.FeatureClass) -> None:
    """Checked out in a version of one's own, the check-in always passes; the merge then finds the conflict."""
    base = _grid(15)
    fid = F.insert_feature(conn, horizons, base)
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "mine")
    conn.commit()
    with tgsis.in_version(conn, "mine"):
        co = tgsis.checkout(conn, fid)
    theirs = base.vertices.copy()
    theirs[100, 2] = 7.0  # the same vertex as below, elsewhere: a region conflict (disjoint edits merge by region)
    tgsis.save_feature(conn, horizons, fid, tgsis.Surface(theirs, base.cells, vertex_properties=base.vertex_properties))
    conn.commit()  # DEFAULT changed it meanwhile
    mine = co.mesh.copy()
    mine.vertices[100, 2] = -7.0
    assert tgsis.checkin(conn, co, mine).version == "mine"
    conn.commit()
    with pytest.raises(tgsis.UnsolvedConflictsError, match=str(fid)):
        tgsis.merge_version(conn, "mine")
    conn.rollback()
    assert [c.objectkey for c in tgsis.find_conflicts(conn, "mine")] == [str(fid)]


def test_bad_calls_to_the_check_in_functions_of_sql(conn: Conn, horizons: F.FeatureClass) -> None:
    """What psql users call directly: our SQLSTATEs, and nothing changed."""
    fid = F.insert_feature(conn, horizons, _grid(5))
    evolving = tgsis.EvolvingSurface(
        [tgsis.TopologyPeriod([0.0, 1.0], _grid(3).cells, [_grid(3).vertices, _grid(3).vertices + 1])]
    )
    moving = F.insert_feature(conn, F.create_feature_class(conn, "moving", "SURFACE", time_model="EVOLVING"), evolving)
    conn.commit()
    state = _fingerprint(conn, fid)
    calls = [
        ("SELECT tgsis.object_fingerprint(%s)", (moving,), "TG100", "temporal"),
        ("SELECT tgsis.check_unchanged(%s, NULL)", (fid,), "TG100", "needs a geoid and the fingerprint"),
        ("SELECT tgsis.check_unchanged(%s, 'x')", (fid,), "TG304", f"feature {fid} was changed"),
        ("SELECT tgsis.check_unchanged(%s, 'x')", (fid + 999,), "TG304", "was deleted"),
        ("SELECT tgsis.table_fingerprint('tgsis', 'nope', 'geoid', 'id', ARRAY[1::bigint])", (), "TG200", "nope"),
        ("SELECT tgsis.delete_object_rows('tgsis', 'nope', 'geoid', ARRAY[1::bigint])", (), "TG200", "nope"),
        (
            "SELECT tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', ARRAY[%s::bigint], 'vrtxid', NULL)",
            (fid,),
            "TG100",
            "id column and ids together",
        ),
    ]
    for query, params, code, text in calls:
        with pytest.raises(tgsis.Error, match=text) as raised:
            with tgsis.errors.reraise():
                conn.execute(query, params)
        assert raised.value.sqlstate == code, query
        conn.rollback()
        assert _fingerprint(conn, fid) == state
    assert conn.execute("SELECT tgsis.object_fingerprint(NULL)").fetchone() == (None,)
    # the id-restricted delete removes exactly those rows (of a table stored in chunks: tgsis.write_object_rows,
    # which rewrites the chunk they are in)
    if conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,):
        assert conn.execute(
            "SELECT tgsis.write_object_rows('vrtx', %s, ARRAY[1, 2]::bigint[], '{}')", (fid,)
        ).fetchone() == (1,)
    else:
        assert conn.execute(
            "SELECT tgsis.delete_object_rows('tgsis', 'vrtx', 'geoid', ARRAY[%s::bigint], 'vrtxid', ARRAY[1, 2]::bigint[])",
            (fid,),
        ).fetchone() == (2,)
    assert conn.execute("SELECT count(*) FROM tgsis.vrtx WHERE geoid = %s", (fid,)).fetchone() == (23,)
