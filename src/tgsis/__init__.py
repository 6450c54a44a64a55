"""tgsis: a spatio-temporal geoscience information system on PostgreSQL.

Geological objects (points, lines, triangulated surfaces, tetrahedral solids)
with topology and properties, their change through time, and many versions of
them in long transactions, stored by the ``tgsis`` PostgreSQL extension and
reached from Python through this package.

>>> import tgsis                                          # doctest: +SKIP
>>> with tgsis.connect() as conn:                         # local server if no DSN
...     print(conn.execute("select tgsis.version()").fetchone())
...     fc = tgsis.create_feature_class(conn, "horizons", "SURFACE")
...     fid = tgsis.insert_feature(conn, fc, tgsis.Surface(vertices, triangles))
"""

from __future__ import annotations

import importlib
import logging
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _package_version
from typing import TYPE_CHECKING, Any

from tgsis.compare import MeshDiff, MeshIndex, compare_meshes
from tgsis.temporal import EvolvingSurface, Period, SurfaceSeries, TopologyPeriod, WrittenSeries, write_series_pvd
from tgsis.mesh import (
    GeometryCollection,
    Geotype,
    LineSet,
    Mesh,
    MeshReport,
    PointSet,
    Surface,
    TetraMesh,
    mesh_class,
)
from tgsis.convert import as_mesh
from tgsis.gmaps import EvolvingGMap, GMap, GMapPeriod, GMapReport
from tgsis.gmaps import extrude as extrude_gmap
from tgsis.gmaps import slice as slice_gmap
from tgsis.errors import (
    AlreadyExistsError,
    ConcurrentChangeError,
    DatabaseError,
    Error,
    FileFormatError,
    InstallationError,
    InUseError,
    InvalidGeometryError,
    InvalidGMapError,
    InvalidInputError,
    InvalidNameError,
    InvalidPropertyError,
    LocalServerError,
    MissingPrivilegeError,
    NotFoundError,
    NotVersionedError,
    ObjectLockedError,
    CheckoutConflictError,
    ReadOnlyRevisionError,
    SkippedObjectWarning,
    UnsolvedConflictsError,
    VersioningError,
)


if TYPE_CHECKING:  # the database layer, for type checkers; at run time it loads on first use (below)
    from tgsis.db import (
        ExtensionSources,
        InstalledVersion,
        InstallResult,
        LocalServer,
        connect,
        find_binaries,
        install,
        installed_version,
        uninstall,
    )
    from tgsis.db.versions import (
        Compressed,
        Conflict,
        Difference,
        ObjectLock,
        Version,
        VersionGrant,
        VersionedTable,
        at_revision,
        compress_versions,
        conflict_rows,
        create_version,
        delete_version,
        diff_versions,
        disable_feature_versioning,
        disable_versioning,
        enable_feature_versioning,
        enable_versioning,
        find_conflicts,
        goto_revision,
        goto_version,
        grant_version,
        has_version_privilege,
        in_version,
        list_versions,
        lock_objects,
        merge_version,
        object_locks,
        refresh_version,
        resolve_conflict,
        revisions,
        revoke_version,
        save_revision,
        set_version_owner,
        set_version_validity,
        unlock_objects,
        version_believed_at,
        version_chain,
        version_privileges,
        versioned_tables,
        viewing_revision,
        working_revision,
        working_version,
    )
    from tgsis.db.features import (
        Feature,
        FeatureClass,
        Property,
        create_feature_class,
        delete_feature,
        drop_feature_class,
        features_in_box,
        fetch_feature,
        fetch_features,
        get_feature_class,
        insert_feature,
        list_feature_classes,
    )
    from tgsis.db.checkin import (
        CheckinResult,
        Checkout,
        CheckoutToken,
        SaveResult,
        checkin,
        checkout,
        save_feature,
    )
    from tgsis.db.compare import GeometryChanges, compare_stored, compare_versions
    from tgsis.db.temporal import (
        add_instant,
        append_period,
        delete_instant,
        delete_period,
        export_series,
        features_at,
        fetch_evolving,
        fetch_series,
        class_property_periods,
        first_times,
        frames_at,
        get_at,
        instants,
        lifespan,
        property_periods,
        surfaces_at,
    )
    from tgsis.db.gmaps import (GMapProblem, fetch_gmap, fetch_md_gmap, gmap_at, gmap_cells, gmap_check, insert_gmap,
                                md_in_box, md_vertices_in_box)

# The database layer (and psycopg) is imported on first use of one of its
# names, so that the numpy modules (tgsis.mesh, compare, edits, temporal,
# interpolation, formats) load without it (tests/test_pure_imports.py).
_LAZY: dict[str, str] = {
    "ExtensionSources": "tgsis.db",
    "InstalledVersion": "tgsis.db",
    "InstallResult": "tgsis.db",
    "LocalServer": "tgsis.db",
    "connect": "tgsis.db",
    "find_binaries": "tgsis.db",
    "install": "tgsis.db",
    "installed_version": "tgsis.db",
    "uninstall": "tgsis.db",
    "Compressed": "tgsis.db.versions",
    "Conflict": "tgsis.db.versions",
    "Difference": "tgsis.db.versions",
    "ObjectLock": "tgsis.db.versions",
    "Version": "tgsis.db.versions",
    "VersionGrant": "tgsis.db.versions",
    "VersionedTable": "tgsis.db.versions",
    "at_revision": "tgsis.db.versions",
    "compress_versions": "tgsis.db.versions",
    "conflict_rows": "tgsis.db.versions",
    "create_version": "tgsis.db.versions",
    "delete_version": "tgsis.db.versions",
    "diff_versions": "tgsis.db.versions",
    "disable_feature_versioning": "tgsis.db.versions",
    "disable_versioning": "tgsis.db.versions",
    "enable_feature_versioning": "tgsis.db.versions",
    "enable_versioning": "tgsis.db.versions",
    "find_conflicts": "tgsis.db.versions",
    "goto_revision": "tgsis.db.versions",
    "goto_version": "tgsis.db.versions",
    "grant_version": "tgsis.db.versions",
    "has_version_privilege": "tgsis.db.versions",
    "in_version": "tgsis.db.versions",
    "list_versions": "tgsis.db.versions",
    "lock_objects": "tgsis.db.versions",
    "merge_version": "tgsis.db.versions",
    "object_locks": "tgsis.db.versions",
    "refresh_version": "tgsis.db.versions",
    "resolve_conflict": "tgsis.db.versions",
    "revisions": "tgsis.db.versions",
    "revoke_version": "tgsis.db.versions",
    "save_revision": "tgsis.db.versions",
    "set_version_owner": "tgsis.db.versions",
    "set_version_validity": "tgsis.db.versions",
    "unlock_objects": "tgsis.db.versions",
    "version_believed_at": "tgsis.db.versions",
    "version_chain": "tgsis.db.versions",
    "version_privileges": "tgsis.db.versions",
    "versioned_tables": "tgsis.db.versions",
    "viewing_revision": "tgsis.db.versions",
    "working_revision": "tgsis.db.versions",
    "working_version": "tgsis.db.versions",
    "Feature": "tgsis.db.features",
    "FeatureClass": "tgsis.db.features",
    "Property": "tgsis.db.features",
    "create_feature_class": "tgsis.db.features",
    "delete_feature": "tgsis.db.features",
    "drop_feature_class": "tgsis.db.features",
    "features_in_box": "tgsis.db.features",
    "fetch_feature": "tgsis.db.features",
    "fetch_features": "tgsis.db.features",
    "get_feature_class": "tgsis.db.features",
    "insert_feature": "tgsis.db.features",
    "list_feature_classes": "tgsis.db.features",
    "CheckinResult": "tgsis.db.checkin",
    "Checkout": "tgsis.db.checkin",
    "CheckoutToken": "tgsis.db.checkin",
    "SaveResult": "tgsis.db.checkin",
    "checkin": "tgsis.db.checkin",
    "checkout": "tgsis.db.checkin",
    "save_feature": "tgsis.db.checkin",
    "GeometryChanges": "tgsis.db.compare",
    "compare_stored": "tgsis.db.compare",
    "compare_versions": "tgsis.db.compare",
    "add_instant": "tgsis.db.temporal",
    "append_period": "tgsis.db.temporal",
    "delete_instant": "tgsis.db.temporal",
    "delete_period": "tgsis.db.temporal",
    "export_series": "tgsis.db.temporal",
    "features_at": "tgsis.db.temporal",
    "fetch_evolving": "tgsis.db.temporal",
    "fetch_series": "tgsis.db.temporal",
    "class_property_periods": "tgsis.db.temporal",
    "first_times": "tgsis.db.temporal",
    "frames_at": "tgsis.db.temporal",
    "get_at": "tgsis.db.temporal",
    "instants": "tgsis.db.temporal",
    "lifespan": "tgsis.db.temporal",
    "property_periods": "tgsis.db.temporal",
    "surfaces_at": "tgsis.db.temporal",
    "GMapProblem": "tgsis.db.gmaps",
    "fetch_gmap": "tgsis.db.gmaps",
    "gmap_at": "tgsis.db.gmaps",
    "gmap_cells": "tgsis.db.gmaps",
    "gmap_check": "tgsis.db.gmaps",
    "insert_gmap": "tgsis.db.gmaps",
    "fetch_md_gmap": "tgsis.db.gmaps",
    "md_in_box": "tgsis.db.gmaps",
    "md_vertices_in_box": "tgsis.db.gmaps",
}


def __getattr__(name: str) -> Any:
    """The database layer's public names, imported when first asked for (PEP 562)."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'tgsis' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


try:
    __version__ = _package_version("tgsis")
except PackageNotFoundError:  # running from a source tree that is not installed
    from tgsis.db.sqlsource import ExtensionSources as _Sources

    __version__ = _Sources.default().version

logging.getLogger("tgsis").addHandler(logging.NullHandler())

__all__ = [
    "__version__",
    # connections and installation
    "connect",
    "install",
    "installed_version",
    "uninstall",
    "InstallResult",
    "InstalledVersion",
    "ExtensionSources",
    "LocalServer",
    "find_binaries",
    # versions (long transactions)
    "Version",
    "VersionedTable",
    "create_version",
    "delete_version",
    "save_revision",
    "goto_version",
    "goto_revision",
    "working_version",
    "working_revision",
    "viewing_revision",
    "revisions",
    "list_versions",
    "in_version",
    "at_revision",
    "enable_versioning",
    "disable_versioning",
    "versioned_tables",
    "enable_feature_versioning",
    "disable_feature_versioning",
    "Conflict",
    "find_conflicts",
    "resolve_conflict",
    "conflict_rows",
    "merge_version",
    "refresh_version",
    "Difference",
    "diff_versions",
    "set_version_validity",
    "version_chain",
    "version_believed_at",
    "VersionGrant",
    "grant_version",
    "revoke_version",
    "set_version_owner",
    "has_version_privilege",
    "version_privileges",
    "ObjectLock",
    "lock_objects",
    "unlock_objects",
    "object_locks",
    "Compressed",
    "compress_versions",
    # meshes (numpy, no database)
    "Geotype",
    "Mesh",
    "MeshReport",
    "PointSet",
    "LineSet",
    "Surface",
    "TetraMesh",
    "GeometryCollection",
    "mesh_class",
    # pyvista / meshio / trimesh objects to tgsis meshes (tgsis.convert; to_pyvista() and to_meshio() back)
    "as_mesh",
    # mesh comparison (numpy, no database)
    "MeshDiff",
    "MeshIndex",
    "compare_meshes",
    # generalized maps, models 4 and 5 (numpy, no database; more in tgsis.gmaps)
    "GMap",
    "GMapReport",
    "GMapPeriod",
    "EvolvingGMap",
    "extrude_gmap",
    "slice_gmap",
    # G-maps in the database (model 4)
    "insert_gmap",
    "fetch_gmap",
    "gmap_at",
    "gmap_cells",
    "gmap_check",
    "GMapProblem",
    "fetch_md_gmap",
    "md_in_box",
    "md_vertices_in_box",
    # feature classes and features
    "FeatureClass",
    "Property",
    "Feature",
    "create_feature_class",
    "get_feature_class",
    "list_feature_classes",
    "drop_feature_class",
    "insert_feature",
    "fetch_feature",
    "fetch_features",
    "features_in_box",
    "delete_feature",
    # saving by difference, check-out and check-in
    "save_feature",
    "SaveResult",
    "checkout",
    "checkin",
    "Checkout",
    "CheckoutToken",
    "CheckinResult",
    "GeometryChanges",
    "compare_stored",
    "compare_versions",
    # time: surfaces at instants (model 2) and evolving surfaces (model 3)
    "SurfaceSeries",
    "EvolvingSurface",
    "TopologyPeriod",
    "add_instant",
    "delete_instant",
    "append_period",
    "delete_period",
    "instants",
    "get_at",
    "surfaces_at",
    "features_at",
    "fetch_series",
    "fetch_evolving",
    "lifespan",
    "frames_at",
    "export_series",
    "write_series_pvd",
    "WrittenSeries",
    "Period",
    "property_periods",
    "class_property_periods",
    "first_times",
    # errors
    "Error",
    "AlreadyExistsError",
    "ConcurrentChangeError",
    "DatabaseError",
    "FileFormatError",
    "SkippedObjectWarning",
    "InstallationError",
    "InUseError",
    "InvalidGeometryError",
    "InvalidGMapError",
    "InvalidInputError",
    "InvalidNameError",
    "InvalidPropertyError",
    "LocalServerError",
    "MissingPrivilegeError",
    "NotFoundError",
    "NotVersionedError",
    "ObjectLockedError",
    "CheckoutConflictError",
    "ReadOnlyRevisionError",
    "UnsolvedConflictsError",
    "VersioningError",
]
