"""Model 1's rows: how static meshes and collections become rows of ``tgsis.geometry``, ``vrtx``,
the simplex tables, ``atom``, ``part`` and the class's property tables, and back.

Shared by :mod:`tgsis.db.features` (upload, download) and
:mod:`tgsis.db.checkin` (check-in by difference); private to ``tgsis.db``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
import numpy.typing as npt
import psycopg
from psycopg import sql

from tgsis.arguments import no_nul
from tgsis.db._chunk_transfer import ObjectRows, chunked_tables, repeated_corners, rows_request, upload_chunks
from tgsis.db._property_chunks import property_chunks, property_request, upload_properties, write_property_rows
from tgsis.db._transfer import (
    Packed,
    PartRequest,
    Storage,
    columns_out_all,
    concat,
    local_positions,
    row_keys,
    rows_by_geoid,
    stored_cell_properties,
)
from tgsis.db.classes import FeatureClass, Property, stores_part_column
from tgsis.db.meaning import Meaning, part_runs, parts_from_runs, restore_meaning
from tgsis.errors import InvalidGeometryError, InvalidPropertyError
from tgsis.mesh import Geometry, GeometryCollection, Geotype, Mesh, mesh_class

Conn = psycopg.Connection[Any]


SIMPLEX = {
    Geotype.MULTIPOINT: ("point", "pointid"),
    Geotype.MULTILINESTRING: ("segment", "segid"),
    Geotype.SURFACE: ("trgl", "trglid"),
    Geotype.MULTITETRA: ("tetra", "tetraid"),
}


#: metadata key of a collection member that has only some of its class's properties: their names
MEMBER_PROPERTIES_KEY = "tgsis_properties"


def member_class(fc: FeatureClass, member: Mesh) -> FeatureClass:
    """The class as one member of a collection sees it: the class's properties that the member has."""
    cells = stored_cell_properties(fc, member)
    kept = tuple(
        p
        for p in fc.cell_properties
        if p.name in (member.vertex_properties if fc.alignment_of(p) == "VERTEX" else cells)
    )
    return fc if len(kept) == len(fc.cell_properties) else replace(fc, cell_properties=kept)


def with_property_names(meaning: Meaning, fc: FeatureClass, member_class: FeatureClass) -> Meaning:
    """A member's meaning, with the names of the properties it has when it lacks some of the class's."""
    if member_class is fc:
        return meaning
    return replace(
        meaning,
        metadata={**(meaning.metadata or {}), MEMBER_PROPERTIES_KEY: [p.name for p in member_class.cell_properties]},
    )


def member_label(index: int, mesh: Mesh) -> str:
    """How messages name member ``index`` of a collection."""
    named = f" {mesh.name!r}" if mesh.name else ""
    return f"member {index} ({type(mesh).__name__}{named})"


def stored_bounds(geometry: Geometry, meanings: Sequence[Meaning]) -> list[float] | None:
    """The box of a mesh or collection in storage's convention (elevation): Depth members' z negated."""
    members = geometry.members if isinstance(geometry, GeometryCollection) else (geometry,)
    boxes = []
    for member, meaning in zip(members, meanings):
        if member.n_vertices:
            box = member.bounds()
            if meaning.depth:
                box = np.array([[box[0, 0], box[0, 1], -box[1, 2]], [box[1, 0], box[1, 1], -box[0, 2]]])
            boxes.append(box)
    if not boxes:
        return None
    stacked = np.stack(boxes)
    return [float(v) for v in np.concatenate([stacked[:, 0].min(axis=0), stacked[:, 1].max(axis=0)])]


def new_static_geometry(
    conn: Conn,
    geometry: Geometry,
    name: str | None,
    meaning: Meaning,
    member_meanings: Sequence[Meaning],
    *,
    collection: int | None = None,
    feature_class: str | None = None,
) -> int:
    """Insert the ``tgsis.geometry`` row of a mesh or collection (bbox and counts from it); return its geoid.

    ``meaning`` is the geometry's own (z convention, coordinate system,
    colour, metadata); ``member_meanings`` those of its members (of a mesh:
    its own), whose z conventions give the stored box. ``feature_class``
    names the class the geometry is stored for: one registered without
    versioning gives it a geoid of no version (members inherit their
    collection's).
    """
    bounds = stored_bounds(geometry, member_meanings)
    geoids: list[int] | None = [] if isinstance(geometry, GeometryCollection) else None  # members come next
    row = conn.execute(
        "SELECT tgsis.new_geometry(%s, %s, %s, %s, %s, %s, %s, 'STATIC', false, %s::real[], %s, "
        "%s::jsonb, %s::jsonb, %s)",
        (
            geometry.geotype.value,
            no_nul("geometry name", name),
            bounds,
            geometry.n_vertices,
            geometry.n_cells,
            geoids,
            collection,
            meaning.color,
            meaning.zpositive,
            meaning.crs_json(),
            meaning.metadata_json(),
            feature_class,
        ),
    ).fetchone()
    assert row is not None
    return int(row[0])


def copy_meshes(
    conn: Conn,
    fc: FeatureClass,
    geoids: Sequence[int],
    meshes: Sequence[Mesh],
    cell_values: Sequence[Mapping[str, npt.NDArray[Any]]],
    storage: Storage,
    meanings: Sequence[Meaning],
) -> None:
    """COPY the vertices, simplices and cell properties of meshes: one COPY per table, whatever their number.

    Parameters
    ----------
    geoids : sequence of int
        Geometry row of each mesh.
    meshes : sequence of Mesh
        Of any of the four types.
    cell_values : sequence of mapping
        Per mesh, the class's property arrays from :func:`aligned_properties`:
        (n_i,) for VERTEX alignment, (m_i,) for CELL.
    storage : Storage
        Plain or versioned targets.
    meanings : sequence of Meaning
        Per mesh: Depth meshes are stored with z negated (elevation); their
        atoms go to ``tgsis.atom``.
    """
    vertex_geoids, vertex_ids = row_keys(geoids, [m.n_vertices for m in meshes])
    xyz = concat([m.vertices for m in meshes])
    if any(meaning.depth for meaning in meanings):
        xyz = xyz.copy()
        flip = np.repeat([meaning.depth for meaning in meanings], [m.n_vertices for m in meshes])
        xyz[flip, 2] = -xyz[flip, 2]  # exact: only the sign bit changes
    chunked = chunked_tables(conn)
    if "vrtx" in chunked:  # the chunks of every mesh in one COPY (docs/storage.md, "What each bulk path does")
        starts = np.cumsum([0, *(m.n_vertices for m in meshes)])
        upload_chunks(
            conn,
            "vrtx",
            [
                ObjectRows(
                    geoid,
                    np.arange(m.n_vertices, dtype=np.int64),
                    {name: xyz[starts[i] : starts[i + 1], j] for j, name in enumerate(("x", "y", "z"))},
                )
                for i, (geoid, m) in enumerate(zip(geoids, meshes))
            ],
            storage,
        )
    else:
        storage.copy(
            conn,
            "tgsis",
            "vrtx",
            [
                ("geoid", vertex_geoids, "int8"),
                ("vrtxid", vertex_ids, "int8"),
                ("x", xyz[:, 0], "float8"),
                ("y", xyz[:, 1], "float8"),
                ("z", xyz[:, 2], "float8"),
            ],
        )
    for geotype in dict.fromkeys(m.geotype for m in meshes):  # each simplex table once, in member order
        group = [i for i, m in enumerate(meshes) if m.geotype == geotype]
        table, key = SIMPLEX[geotype]
        k = meshes[group[0]].cell_size
        rows = [simplex_rows(geoids[i], meshes[i], table) for i in group]  # checked on both paths
        if table in chunked:
            upload_chunks(conn, table, rows, storage)
            continue
        cell_geoids, cell_ids = row_keys([geoids[i] for i in group], [meshes[i].n_cells for i in group])
        cells = concat([meshes[i].cells for i in group])
        storage.copy(
            conn,
            "tgsis",
            table,
            [
                ("geoid", cell_geoids, "int8"),
                (key, cell_ids, "int8"),
                *((f"vrtxid{j + 1}", cells[:, j], "int8") for j in range(k)),
            ],
        )
    for alignment in ("VERTEX", "CELL"):  # one table per alignment (the class's own: cellprotable)
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        # collection members may have some of the properties each: one COPY per set of properties
        groups: dict[tuple[str, ...], list[int]] = {}
        for i, values in enumerate(cell_values):
            groups.setdefault(tuple(p.name for p in props if p.name in values), []).append(i)
        layout = property_chunks(conn, fc, protable)
        # vector properties in chunks have no client encoding (layout None): the server writes them, set-based
        serverside = layout is None and any(p.size > 1 for p in props) and _stored_in_chunks(conn, fc.schema, protable)
        if (layout is not None and layout.insertable and layout.versioned) or serverside:
            # versioned, in chunks: each new object's rows in one call, its chunks written once in the
            # working revision (the face's checks on the server), not one chunk rewrite per row
            for names, group in groups.items():
                for i in group if names else ():
                    n = meshes[i].n_vertices if alignment == "VERTEX" else meshes[i].n_cells
                    write_property_rows(
                        conn,
                        fc.schema,
                        protable,
                        geoids[i],
                        np.zeros(0, dtype=np.int64),
                        [
                            ("_geoid", np.full(n, geoids[i], dtype=np.int64), "int8"),
                            ("_idx", np.arange(n, dtype=np.int64), "int8"),
                            *((p.name, cell_values[i][p.name], p.wire) for p in props if p.name in names),
                        ],
                    )
            continue
        if layout is not None and layout.insertable:  # stored in chunks: whole chunks, one COPY for every mesh
            members = [i for names, group in groups.items() if names for i in group]
            upload_properties(
                conn,
                layout,
                [geoids[i] for i in members],
                [meshes[i].n_vertices if alignment == "VERTEX" else meshes[i].n_cells for i in members],
                [{p.name: cell_values[i][p.name] for p in props if p.name in cell_values[i]} for i in members],
            )
            continue
        for names, group in groups.items():
            if not names:
                continue
            counts = [meshes[i].n_vertices if alignment == "VERTEX" else meshes[i].n_cells for i in group]
            prop_geoids, prop_ids = row_keys([geoids[i] for i in group], counts)
            storage.copy(
                conn,
                fc.schema,
                protable,
                [
                    ("_geoid", prop_geoids, "int8"),
                    ("_idx", prop_ids, "int8"),
                    *(
                        (p.name, concat([cell_values[i][p.name] for i in group]), p.wire)
                        for p in props
                        if p.name in names
                    ),
                ],
            )
    copy_extras(conn, fc, geoids, meshes, meanings, storage)


def _stored_in_chunks(conn: Conn, schema: str, table: str) -> bool:
    """Whether the class's property table ``schema.table`` is the face of ``tgsis.store_class_in_chunks``."""
    row = conn.execute("SELECT tgsis.stored_in_chunks(%s, %s)", (schema, table)).fetchone()
    return bool(row is not None and row[0])


def simplex_rows(geoid: int, mesh: Mesh, table: str) -> ObjectRows:
    """A mesh's simplices as the rows of its chunked simplex table: ids 0..m-1, one corner column per vertex.

    Checks what the row table's CHECK checks on every row (``<table>_distinct_vertices``: a cell names k
    distinct vertices), which a mesh changed after it was made may break: the chunk upload has no such
    CHECK, and the row upload's would fail with a raw ``23514``.

    Raises
    ------
    InvalidGeometryError
        A cell names one vertex twice (nothing is written).
    """
    cells = np.asarray(mesh.cells, dtype=np.int64)
    k = mesh.cell_size
    repeated = repeated_corners([cells[:, j] for j in range(k)])
    if repeated.any():
        row = int(np.flatnonzero(repeated)[0])
        raise InvalidGeometryError(
            f"geometry {geoid}: {mesh.cell_name} {row} uses a vertex twice: {cells[row].tolist()}",
            detail=f"{int(repeated.sum())} cells repeat a vertex (tgsis.{table}: {table}_distinct_vertices)",
        )
    return ObjectRows(geoid, np.arange(len(cells), dtype=np.int64), {f"vrtxid{j + 1}": cells[:, j] for j in range(k)})


def extra_rows(
    fc: FeatureClass,
    geoid: int,
    mesh: Mesh,
    meaning: Meaning,
    vertex_ids: npt.NDArray[np.int64] | None = None,
    cell_ids: npt.NDArray[np.int64] | None = None,
) -> tuple[list[tuple[int, ...]], list[tuple[int, ...]]]:
    """The ``tgsis.atom`` rows ``(geoid, vrtxid, refid, patom)`` and ``tgsis.part`` rows ``(geoid, firstid, lastid, part)`` of a mesh.

    ``vertex_ids``/``cell_ids`` give the database id of each vertex and cell
    (default: 0..n-1, as a first upload numbers them); a run of parts never
    spans a gap in the cell ids.
    """
    atoms = [
        (
            geoid,
            int(vertex_ids[a]) if vertex_ids is not None else a,
            int(vertex_ids[r]) if vertex_ids is not None else r,
            int(a in meaning.patoms),
        )
        for a, r in meaning.atoms
    ]
    parts: list[tuple[int, ...]] = []
    if "part" in mesh.cell_properties and not stores_part_column(fc):
        ids = cell_ids if cell_ids is not None else np.arange(mesh.n_cells, dtype=np.int64)
        parts = part_rows(geoid, ids, mesh.cell_properties["part"])
    return list(atoms), parts


def part_rows(geoid: int, cell_ids: npt.NDArray[np.int64], values: npt.NDArray[Any]) -> list[tuple[int, ...]]:
    """The ``tgsis.part`` rows ``(geoid, firstid, lastid, part)`` of cells ``cell_ids`` (m,) with part numbers ``values`` (m,).

    A run never spans a gap in the cell ids.
    """
    order = np.argsort(cell_ids, kind="stable")
    ids, values = np.asarray(cell_ids)[order], np.asarray(values)[order]
    firsts, _, _ = part_runs(values)
    if not len(firsts):
        return []
    breaks = np.flatnonzero(np.diff(ids) != 1) + 1
    starts = np.union1d(firsts, breaks).astype(np.int64)
    ends = np.concatenate([starts[1:] - 1, [len(ids) - 1]]).astype(np.int64)
    numbers = values[starts].astype(np.int64)
    return [(geoid, int(f), int(last), int(n)) for f, last, n in zip(ids[starts], ids[ends], numbers)]


def copy_extra_rows(
    conn: Conn, storage: Storage, atoms: Sequence[tuple[int, ...]], parts: Sequence[tuple[int, ...]]
) -> None:
    """COPY rows of :func:`extra_rows` into ``tgsis.atom`` and ``tgsis.part``."""
    if atoms:
        columns = np.asarray(atoms, dtype=np.int64).T
        storage.copy(
            conn,
            "tgsis",
            "atom",
            [
                ("geoid", columns[0], "int8"),
                ("vrtxid", columns[1], "int8"),
                ("refid", columns[2], "int8"),
                ("patom", columns[3] != 0, "bool"),
            ],
        )
    if parts:
        columns = np.asarray(parts, dtype=np.int64).T
        storage.copy(
            conn,
            "tgsis",
            "part",
            [
                ("geoid", columns[0], "int8"),
                ("firstid", columns[1], "int8"),
                ("lastid", columns[2], "int8"),
                ("part", columns[3].astype(np.int32), "int4"),
            ],
        )


def copy_extras(
    conn: Conn,
    fc: FeatureClass,
    geoids: Sequence[int],
    meshes: Sequence[Mesh],
    meanings: Sequence[Meaning],
    storage: Storage,
) -> None:
    """COPY the atoms (``tgsis.atom``) and parts (``tgsis.part``) of freshly uploaded meshes."""
    atoms: list[tuple[int, ...]] = []
    parts: list[tuple[int, ...]] = []
    for geoid, mesh, meaning in zip(geoids, meshes, meanings):
        more_atoms, more_parts = extra_rows(fc, geoid, mesh, meaning)
        atoms += more_atoms
        parts += more_parts
    copy_extra_rows(conn, storage, atoms, parts)


@dataclass(frozen=True)
class Part:
    """A geometry to download: its geotype, name, how messages name it, and what its file meant."""

    geotype: Geotype
    name: str | None
    label: str
    zpositive: str | None = None
    crs: list[str] | None = None
    color: tuple[float | None, ...] | None = None
    metadata: dict[str, Any] | None = None
    properties: tuple[str, ...] | None = None  # a collection member's properties when it lacks some (None: all)


#: the columns of tgsis.geometry that part_meaning reads, after geotype and name
MEANING_COLUMNS = "g.zpositive, g.crs, g.colorred, g.colorgreen, g.colorblue, g.metadata"


def part_meaning(row: Sequence[Any], member: bool = False) -> dict[str, Any]:
    """Part keyword arguments from the values of :data:`MEANING_COLUMNS` (``member``: of a collection member)."""
    meaning = {
        "zpositive": row[0],
        "crs": row[1],
        "color": tuple(row[2:5]) if row[2] is not None else None,
        "metadata": row[5],
    }
    if member and isinstance(row[5], dict) and MEMBER_PROPERTIES_KEY in row[5]:
        metadata = dict(row[5])
        names = metadata.pop(MEMBER_PROPERTIES_KEY)
        meaning["metadata"] = metadata or None
        meaning["properties"] = tuple(str(n) for n in names) if isinstance(names, list) else ()
    return meaning


def collection_members(conn: Conn, fc: FeatureClass, wanted: Sequence[int]) -> dict[int, list[tuple[int, Part]]]:
    """Members of each collection in ``wanted``, in stored order: ``{collection: [(member geoid, part)]}``."""
    rows = conn.execute(
        f"SELECT c.geoid, m.geoid, g.geotype, g.geoname, {MEANING_COLUMNS} FROM tgsis.geometry c "
        "CROSS JOIN LATERAL unnest(c.geoids) WITH ORDINALITY AS m(geoid, ord) "
        "LEFT JOIN tgsis.geometry g ON g.geoid = m.geoid "
        "WHERE c.geoid = ANY(%s) ORDER BY c.geoid, m.ord",
        (list(wanted),),
        binary=True,  # float values (properties, colours) bit for bit, whatever the session's extra_float_digits
    ).fetchall()
    members: dict[int, list[tuple[int, Part]]] = {int(g): [] for g in wanted}
    for cid, mid, geotype, geoname, *meaning in rows:
        where = f"member {len(members[cid])} (geometry {mid}) of feature {cid} of class {fc.name}"
        if geotype is None:
            raise InvalidGeometryError(f"{where} does not exist", hint=f"SELECT * FROM tgsis.check_geometry({cid})")
        if geotype == Geotype.GEOMETRYCOLLECTION.value:
            raise InvalidGeometryError(
                f"{where} is a GEOMETRYCOLLECTION: collections do not nest",
                hint=f"SELECT * FROM tgsis.check_geometry({cid})",
            )
        members[cid].append((int(mid), Part(Geotype(geotype), geoname, where, **part_meaning(meaning, member=True))))
    empty = [cid for cid, listed in members.items() if not listed]
    if empty:
        raise InvalidGeometryError(
            f"feature(s) {empty} of class {fc.name} are collections without members",
            hint="a collection lists its members in tgsis.geometry.geoids",
        )
    return members


@dataclass
class Download:
    """What the queries of :func:`download` returned (columns as numpy arrays)."""

    vertices: list[npt.NDArray[Any]]
    cells: dict[Geotype, list[npt.NDArray[Any]]]
    #: per (alignment, property names): _geoid, _idx, one array per property (collection members may
    #: have some of the class's properties each: one COPY per set)
    properties: dict[tuple[str, tuple[str, ...]], list[npt.NDArray[Any]]]
    atoms: dict[int, list[tuple[int, int, bool]]] = field(default_factory=dict)
    parts: dict[int, list[tuple[int, int, int]]] = field(default_factory=dict)


def download(conn: Conn, fc: FeatureClass, parts: Mapping[int, Part]) -> Download:
    """Download the vertices, simplices and cell properties of the geometries ``parts``.

    One query (:func:`columns_out_all`): the vertices, the simplices of each
    geotype and each property table are its parts, each giving a geometry's
    column as one binary value, which the server may compute side by side;
    a bounded number of parts whatever the number of geometries. A table
    stored in chunks gives its chunk rows (:func:`rows_request`), decoded
    here: one statement, so one snapshot in any isolation level.
    """
    id_list = sql.Literal(list(parts))
    chunked = chunked_tables(conn)
    requests: list[PartRequest] = [
        rows_request(
            conn, "vrtx", [("vrtxid", "int8"), ("x", "float8"), ("y", "float8"), ("z", "float8")], list(parts), chunked
        )
    ]
    geotypes = list(dict.fromkeys(part.geotype for part in parts.values()))
    for geotype in geotypes:
        table, key = SIMPLEX[geotype]
        cell_cols = [f"vrtxid{i + 1}" for i in range(mesh_class(geotype).cell_size)]
        group = [g for g, part in parts.items() if part.geotype == geotype]
        requests.append(rows_request(conn, table, [(c, "int8") for c in (key, *cell_cols)], group, chunked))
    property_keys: list[tuple[str, tuple[str, ...]]] = []
    for alignment in ("VERTEX", "CELL"):  # one part per property table (and set of properties)
        props, protable = fc.aligned(alignment), fc.property_table(alignment)
        if not props or protable is None:
            continue
        for names, members in property_groups(props, parts).items():
            if names:
                property_keys.append((alignment, names))
                # stored in chunks: read from them (the face's rows, decoded here), else the rows
                chunked_request = property_request(conn, fc, protable, names, members)
                requests.append(
                    chunked_request
                    if chunked_request is not None
                    else Packed(
                        fc.qualified(protable),
                        "_geoid",
                        [("_idx", "int8"), *((p.name, p.wire) for p in props if p.name in names)],
                        members,
                    )
                )
    vertices, *rest = columns_out_all(conn, requests)
    cells = dict(zip(geotypes, rest[: len(geotypes)], strict=True))
    properties = dict(zip(property_keys, rest[len(geotypes) :], strict=True))
    atoms: dict[int, list[tuple[int, int, bool]]] = {}
    for geoid, vrtxid, refid, patom in conn.execute(
        sql.SQL(
            "SELECT geoid, vrtxid, refid, patom FROM tgsis.atom WHERE geoid = ANY({}) ORDER BY geoid, vrtxid"
        ).format(id_list)
    ).fetchall():
        atoms.setdefault(int(geoid), []).append((int(vrtxid), int(refid), bool(patom)))
    runs: dict[int, list[tuple[int, int, int]]] = {}
    for geoid, first, last, number in conn.execute(
        sql.SQL(
            "SELECT geoid, firstid, lastid, part FROM tgsis.part WHERE geoid = ANY({}) ORDER BY geoid, firstid"
        ).format(id_list)
    ).fetchall():
        runs.setdefault(int(geoid), []).append((int(first), int(last), int(number)))
    return Download(vertices, cells, properties, atoms, runs)


def names_of(props: Sequence[Property], part: Part) -> tuple[str, ...]:
    """The names of ``props`` that a geometry has (all, but for some collection members)."""
    return tuple(p.name for p in props if part.properties is None or p.name in part.properties)


def property_groups(props: Sequence[Property], parts: Mapping[int, Part]) -> dict[tuple[str, ...], list[int]]:
    """The geometries of ``parts`` by the names of ``props`` they have."""
    groups: dict[tuple[str, ...], list[int]] = {}
    for geoid, part in parts.items():
        groups.setdefault(names_of(props, part), []).append(geoid)
    return groups


def restore_extras(
    mesh: Mesh,
    part: Part,
    data: Download,
    geoid: int,
    vertex_ids: npt.NDArray[np.int64],
    cell_ids: npt.NDArray[np.int64],
    *,
    file_convention: bool = True,
) -> Mesh:
    """The mesh with its parts, atoms and (``file_convention``) its file's z convention and metadata back.

    ``vertex_ids``/``cell_ids`` are the database ids of its vertices and cells, ascending.
    """
    runs = data.parts.get(geoid)
    if runs:
        array = np.asarray(runs, dtype=np.int64)
        values = parts_from_runs(cell_ids, array[:, 0], array[:, 1], array[:, 2])
        mesh.cell_properties = {**mesh.cell_properties, "part": values}
    atoms = data.atoms.get(geoid, [])
    pairs: list[tuple[int, int]] = []
    patoms: list[int] = []
    if atoms:
        array = np.asarray([(a, r) for a, r, _ in atoms], dtype=np.int64)
        flags = np.asarray([p for _, _, p in atoms], dtype=bool)
        found = np.isin(array, vertex_ids).all(axis=1)
        positions = np.searchsorted(vertex_ids, array[found])
        pairs = [(int(a), int(r)) for a, r in positions]
        patoms = [int(a) for (a, _), p in zip(positions, flags[found]) if p]
    if file_convention:
        restore_meaning(mesh, part.zpositive, part.crs, part.color, part.metadata, pairs, patoms, vertex_ids)
    elif pairs:
        mesh.metadata = {**mesh.metadata, "gocad_atoms": [list(p) for p in pairs]}
        if patoms:
            mesh.metadata["gocad_patoms"] = patoms
    return mesh


def assemble_meshes(fc: FeatureClass, parts: Mapping[int, Part], data: Download) -> dict[int, Mesh]:
    """The mesh of every geometry of ``parts`` from the downloaded rows, in stored id order."""
    wanted = list(parts)
    vg, vid, x, y, z = data.vertices
    vertex_rows = rows_by_geoid(vg, vid, wanted)
    prop_rows: dict[int, list[tuple[str, tuple[str, ...], npt.NDArray[np.int64], list[npt.NDArray[Any]]]]] = {}
    for (alignment, names), columns in data.properties.items():
        group = [g for g, part in parts.items() if names_of(fc.aligned(alignment), part) == names]
        for geoid, rows in rows_by_geoid(columns[0], columns[1], group).items():
            prop_rows.setdefault(geoid, []).append((alignment, names, rows, columns))
    xyz = np.stack([x, y, z], axis=1)
    meshes: dict[int, Mesh] = {}
    for geotype, cells in data.cells.items():
        table, _ = SIMPLEX[geotype]
        group = [g for g, part in parts.items() if part.geotype == geotype]
        cell_rows = rows_by_geoid(cells[0], cells[1], group)
        for geoid in group:
            vrows, crows = vertex_rows[geoid], cell_rows[geoid]
            vertex_ids = vid[vrows]
            simplices = np.stack(
                [local_positions(vertex_ids, c[crows], f"{table} rows", geoid) for c in cells[2:]], axis=1
            )
            values: dict[str, dict[str, npt.NDArray[Any]]] = {"VERTEX": {}, "CELL": {}}
            for alignment, names, prows, columns in prop_rows.get(geoid, []):
                target_ids = vertex_ids if alignment == "VERTEX" else cells[1][crows]
                if len(prows) != len(target_ids) or not np.array_equal(columns[1][prows], target_ids):
                    raise InvalidPropertyError(
                        f"{parts[geoid].label}: {fc.property_table(alignment)} has {len(prows)} rows for "
                        f"{len(target_ids)} {'vertices' if alignment == 'VERTEX' else 'cells'}"
                    )
                values[alignment] = {name: columns[2 + i][prows] for i, name in enumerate(names)}
            meshes[geoid] = restore_extras(
                mesh_class(geotype)(
                    xyz[vrows],
                    simplices,
                    vertex_properties=values["VERTEX"],
                    cell_properties=values["CELL"],
                    name=parts[geoid].name,
                ),
                parts[geoid],
                data,
                geoid,
                vertex_ids,
                cells[1][crows],
            )
    return meshes
