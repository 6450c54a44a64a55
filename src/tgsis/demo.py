"""The demo scenario behind ``tgsis demo`` (the README's first command).

Two releases of a fault model, the way a geomodelling team lives them:

1. a fresh database ``tgsis_demo`` on the target server (the local server
   tgsis starts itself when no DSN is given) with tgsis installed;
2. a feature class ``faults`` and the three faults of release 5.3 of the SCEC
   Community Fault Model (real GOCAD TSurf files from ``data/cfm`` of the repository; a
   synthetic stand-in when that folder is missing), stored in DEFAULT;
3. a bounding-box query;
4. versioning switched on, a version ``cfm6.1`` into which release 6.1 is
   checked in over the checked-out 5.3 faults, by difference (a fault that
   was only re-exported writes a handful of rows), and that state saved as a
   revision;
5. what DEFAULT and the version each see, how many rows the version stored,
   and the version tree; a picture of release 6.1 over 5.3, 6.1 coloured by
   its distance from 5.3 (``cfm_release_6.1_over_5.3.png`` in the folder);
6. a fault through geological time (model 3): the first fault of release 5.3
   as it is today and, 2 Ma ago, displaced along strike by a synthetic slip
   growing with depth to 500 m; its shape at -1 Ma computed in SQL, and the
   last 2 Ma written as a ParaView time series (``.pvd``) to a folder;
7. no lost update: two modellers check out the same fault in DEFAULT and both
   edit it; the second check-in is refused and goes into a child version.

Every step uses the public API; the same steps work from ``psql`` and the
``tgsis`` command (see docs/versioning.md).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import psycopg
from psycopg import sql

from tgsis._cfm import CfmFault, load_releases
from tgsis.db import checkin as C
from tgsis.db import features as F
from tgsis.db import temporal as T
from tgsis.db import versions as V
from tgsis.db.connect import resolve_target
from tgsis.db.install import install, installed_version
from tgsis.errors import CheckoutConflictError, InvalidInputError
from tgsis.mesh import Mesh, Surface
from tgsis.temporal import EvolvingSurface, TopologyPeriod

__all__ = ["run_demo", "DEMO_DATABASE"]

DEMO_DATABASE = "tgsis_demo"
#: Synthetic slip of the fault history (metres at the fault's deepest node) over HISTORY (Ma, ages negative).
SLIP = 500.0
HISTORY = (-2.0, 0.0)
#: Coordinates of the two releases are rounded differently: vertices within 1 cm are the same vertex.
TOLERANCE = 0.01


def _demo_conninfo(dsn: str | None) -> str:
    """A fresh, empty database ``tgsis_demo`` on the target server; return its conninfo."""
    from tgsis.scenarios._context import fresh_database

    return fresh_database(dsn, DEMO_DATABASE)


def _store_release(conn: psycopg.Connection[Any], faults: Sequence[CfmFault], release: str) -> dict[str, int]:
    return {
        f.name: F.insert_feature(conn, "faults", f.mesh, {"release": release}, drop_extra_properties=True)
        for f in faults
    }


def _stored_rows(conn: psycopg.Connection[Any]) -> tuple[int, str]:
    """The stored versions of the vertices and triangles (their storage: rows, or chunk versions), and what they are."""
    count = 0
    for table in ("vrtx", "trgl"):
        storage = sql.SQL(V.storage_table(conn, "tgsis", table))  # quoted by tgsis.storage_table
        row = conn.execute(sql.SQL("SELECT count(*) FROM {}").format(storage)).fetchone()
        assert row is not None
        count += int(row[0])
    chunked = conn.execute("SELECT tgsis.stored_in_chunks('vrtx')").fetchone() == (True,)
    return count, "chunk versions" if chunked else "rows"


def _releases_seen(conn: psycopg.Connection[Any]) -> dict[str, str]:
    """Per fault name, the release and size the session's version sees."""
    return {
        f.name or str(f.id): f"release {f.properties['release']} ({f.mesh.n_vertices if f.mesh else 0} vertices)"
        for f in F.fetch_features(conn, "faults")
    }


def _meshes_seen(conn: psycopg.Connection[Any]) -> dict[str, Mesh]:
    """Per fault name, the mesh the session's version sees."""
    return {f.name or str(f.id): f.mesh for f in F.fetch_features(conn, "faults") if isinstance(f.mesh, Mesh)}


def _fault_history(fault: CfmFault) -> tuple[EvolvingSurface, int]:
    """The fault over HISTORY: displaced along strike 2 Ma ago (SLIP at depth, none at the top), as it is today.

    One topology period, two geometry instants; returns it and the index of
    the deepest node (the one that moved most).
    """
    assert isinstance(fault.mesh, Surface)
    today = fault.mesh.vertices
    xy = today[:, :2] - today[:, :2].mean(axis=0)
    strike = np.linalg.svd(xy, full_matrices=False)[2][0]  # horizontal direction of the longest extent
    top, bottom = today[:, 2].max(), today[:, 2].min()
    depth = (top - today[:, 2]) / (top - bottom)  # 0 at the top, 1 at the bottom
    past = today - SLIP * depth[:, None] * np.array([strike[0], strike[1], 0.0])
    period = TopologyPeriod(list(HISTORY), fault.mesh.triangles, [past, today])
    return EvolvingSurface([period], alive=True, name=fault.name), int(np.argmax(depth))


def _store_history(conn: psycopg.Connection[Any], fault: CfmFault, folder: Path) -> list[str]:
    """Step 6: store the fault history, take its shape at the middle time in SQL, export it as a .pvd."""
    history, deepest = _fault_history(fault)
    F.create_feature_class(
        conn,
        "fault_history",
        "SURFACE",
        time_model="EVOLVING",
        time_unit="Ma",
        srs=26911,
        description="faults through geological time (ages in Ma, negative)",
    )
    fid = F.insert_feature(conn, "fault_history", history)
    middle = (HISTORY[0] + HISTORY[1]) / 2
    shape = T.get_at(conn, fid, middle)
    assert shape is not None
    moved = float(np.linalg.norm(shape.vertices[deepest] - fault.mesh.vertices[deepest]))
    written = T.export_series(conn, fid, folder / "fault_history.pvd", start=HISTORY[0], end=HISTORY[1], steps=21)
    return [
        f"5. fault history (model 3): {fault.name} slipping {SLIP:.0f} m at depth from {HISTORY[0]} Ma to today, "
        f"stored as feature {fid} of class fault_history (EVOLVING)",
        f"   at {middle} Ma (SQL snapshot): {shape.n_vertices} vertices, the deepest "
        f"{moved:.0f} m from where it is today",
        f"   {len(written.files)} frames from {HISTORY[0]} to {HISTORY[1]} Ma written to {written.pvd} "
        "(open it in ParaView)",
    ]


def _draw_releases(old: dict[str, Mesh], new: dict[str, Mesh], folder: Path) -> list[str]:
    """Release 6.1 over 5.3 of the fault that changed most: 6.1 coloured by how far each of its vertices lies from 5.3.

    The releases are different meshes (other vertices, other counts), so the
    colour is each 6.1 vertex's distance to the 5.3 surface (exact closest
    point), not a vertex-to-vertex displacement. (The faults lie up to 250 km
    apart: one scene of all three would show none of them.)
    """
    from importlib.util import find_spec

    from tgsis.interpolation.projection import closest_points

    png = folder / "cfm_release_6.1_over_5.3.png"
    if find_spec("matplotlib") is None:
        return ["   no picture of release 6.1 over 5.3: it needs matplotlib (pip install 'tgsis[pictures]')"]
    from tgsis import pictures

    moved = {
        name: closest_points(mesh.vertices, before.vertices, before.triangles).distances
        for name, mesh in new.items()
        if isinstance(mesh, Surface)
        for before in [old.get(name)]
        if isinstance(before, Surface)
    }
    if not moved:
        return ["   no picture of release 6.1 over 5.3: no fault is in both releases"]
    name = max(sorted(moved), key=lambda n: float(moved[n].max()))
    after = new[name]
    assert isinstance(after, Surface)
    # 6.1 alone: 5.3 lies within metres of it and, drawn too, would hide it
    pictures.scene(
        [Surface(after.vertices, after.triangles, name="release 6.1")],
        png,
        title=f"{name}\nrelease 6.1 over 5.3",
        colour=[moved[name]],
        colour_label="distance of 6.1 from 5.3 (m)",
        exaggeration=3.0,
    )
    return [
        f"   {name}: release 6.1 over 5.3, coloured by its distance from 5.3 (up to {moved[name].max():.0f} m), "
        f"drawn to {png}"
    ]


def _no_lost_update(conninfo: str, fid: int) -> list[str]:
    """Step 6: two modellers check the same fault out of DEFAULT; the second check-in cannot overwrite the first."""
    with psycopg.connect(conninfo) as ann, psycopg.connect(conninfo) as bob:
        ann_copy, bob_copy = C.checkout(ann, fid), C.checkout(bob, fid)
        ann_mesh, bob_mesh = ann_copy.mesh.copy(), bob_copy.mesh.copy()
        ann_mesh.vertices[0, 2] += 100.0  # each lifts a different vertex
        bob_mesh.vertices[-1, 2] -= 100.0
        C.checkin(ann, ann_copy, ann_mesh, drop_extra_properties=True)
        try:
            C.checkin(bob, bob_copy, bob_mesh, drop_extra_properties=True)
            refused = "accepted (unexpected)"
        except CheckoutConflictError as exc:
            refused = f"refused: {str(exc).splitlines()[0]}"
        kept = C.checkin(
            bob, bob_copy, bob_mesh, on_conflict="child", child_version="bob_edit", drop_extra_properties=True
        )
    return [
        f"6. no lost update: ann and bob check out feature {fid} in DEFAULT and both edit it",
        f"   ann checks in first; bob's check-in is {refused}",
        f"   with on_conflict='child' bob's edit goes into new version {kept.version} "
        f"({kept.save.rows_written} rows); DEFAULT keeps ann's",
    ]


def run_demo(
    dsn: str | None = None, *, out: Callable[[str], None] = print, folder: str | Path | None = None
) -> list[Path]:
    """Run the demo against the server of ``dsn`` (``None``: the local server), in a database of its own.

    Parameters
    ----------
    dsn : str, optional
        Where to run it; see :func:`tgsis.connect`. The demo creates (and
        first drops) the database ``tgsis_demo`` there.
    out : callable
        Receives each line of the report.
    folder : str or path-like, optional
        Where the demo writes its files (the fault history as ``.pvd``, the
        picture of release 6.1 over 5.3); created if missing. Default: a new
        temporary folder.

    Returns
    -------
    list of Path
        The files written in the folder.
    """
    target = resolve_target(dsn)
    conninfo = _demo_conninfo(dsn)
    source, (old, new) = load_releases()
    with psycopg.connect(conninfo) as conn:
        install(conn)
        current = installed_version(conn)
        assert current is not None
        row = conn.execute("SELECT tgsis.version(), current_setting('server_version')").fetchone()
        assert row is not None
        roles = [
            r[0]
            for r in conn.execute(
                # the group roles users are granted (not tgsis_nobody, which is tgsis's own)
                "SELECT rolname FROM pg_roles WHERE rolname LIKE 'tgsis\\_%' AND rolname <> 'tgsis_nobody' ORDER BY oid"
            ).fetchall()
        ]
        out(f"PostgreSQL {row[1]}, database {DEMO_DATABASE!r} ({target.source})")
        out(f"tgsis {row[0]} (installed as {current.method})")
        out(f"roles: {', '.join(roles)}")
        out(f"data: {source}")

        F.create_feature_class(
            conn,
            "faults",
            "SURFACE",
            feature_properties={"release": "text"},
            srs=26911,
            description="fault surfaces, UTM zone 11 metres, z up",
        )
        V.enable_feature_versioning(conn)
        ids = _store_release(conn, old, "5.3")
        out(
            f"1. stored {len(ids)} faults of release 5.3 in DEFAULT: "
            + ", ".join(f"{name} ({old[i].mesh.n_vertices} vertices)" for i, name in enumerate(ids))
        )

        box = old[0].mesh.bounds() + np.array([[-10_000.0], [10_000.0]])
        found = F.features_in_box(conn, "faults", box)
        names = {fid: name for name, fid in ids.items()}
        out(f"2. faults within 10 km of the box of {old[0].name} (GiST index): {', '.join(names[i] for i in found)}")

        V.create_version(conn, "cfm6.1", description="release 6.1 of the fault model")
        rows_before = _stored_rows(conn)
        report = []
        with V.in_version(conn, "cfm6.1"):
            for fault in new:
                if fault.name not in ids:  # a fault new in this release
                    ids[fault.name] = _store_release(conn, [fault], "6.1")[fault.name]
                    report.append(f"   {fault.name}: new, {fault.mesh.n_vertices} vertices stored")
                    continue
                checked_out = C.checkout(conn, ids[fault.name])
                result = C.checkin(
                    conn, checked_out, fault.mesh, {"release": "6.1"}, tolerance=TOLERANCE, drop_extra_properties=True
                ).save
                counts = result.diff.counts()
                report.append(
                    f"   {fault.name}: {counts['vertices_kept']} of {fault.mesh.n_vertices} vertices kept, "
                    f"{result.vertices_moved} moved; {result.rows_written} rows written "
                    f"(a full upload: {2 * fault.mesh.n_vertices + fault.mesh.n_cells})"
                )
            saved = V.save_revision(conn, "release-6.1")
            seen_in_version = _releases_seen(conn)
            meshes_in_version = _meshes_seen(conn)
        stored = _stored_rows(conn)
        out(
            f"3. version cfm6.1: release 6.1 checked in over {len(new)} fault(s) by difference "
            f"(vertices within {TOLERANCE * 100:.0f} cm are the same), saved as revision {saved}; "
            f"{stored[1]} stored for it: {stored[0] - rows_before[0]}"
        )
        for line in report:
            out(line)
        seen_in_default = _releases_seen(conn)
        for name in sorted(set(seen_in_default) | set(seen_in_version)):
            out(
                f"   {name}: DEFAULT sees {seen_in_default.get(name, 'nothing')}; "
                f"cfm6.1 sees {seen_in_version.get(name, 'nothing')}"
            )
        out("4. version tree:")
        for line in V.format_tree(V.list_versions(conn)).splitlines():
            out("   " + line)
        files = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix="tgsis-demo-"))
        try:
            files.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InvalidInputError(f"cannot create the folder {files}: {exc.strerror or exc}") from exc
        for line in _draw_releases(_meshes_seen(conn), meshes_in_version, files):
            out(line)
        for line in _store_history(conn, old[0], files):
            out(line)
        conn.commit()  # the two modellers below work in sessions of their own
        for line in _no_lost_update(conninfo, ids[old[-1].name]):
            out(line)
    if target.dsn is None:
        out(
            "the local server stops when this command ends; to look around: `tgsis local start`, "
            f'`psql "$(tgsis local dsn)"`, then `\\c {DEMO_DATABASE}`'
        )
        out(f"in a browser: `tgsis view --db {DEMO_DATABASE} --open` (the extra tgsis[view])")
    else:
        out(f"dsn: {conninfo}")
        out("in a browser: `tgsis --dsn DSN view --open`, DSN the one above (the extra tgsis[view])")
    return [p for p in (files / "cfm_release_6.1_over_5.3.png", files / "fault_history.pvd") if p.is_file()]
