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

import logging
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _package_version

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
from tgsis.db.temporal import (
    add_instant,
    delete_instant,
    features_at,
    first_times,
    get_at,
    instants,
    property_periods,
    surfaces_at,
)
from tgsis.temporal import EvolvingSurface, Period, SurfaceSeries, TopologyPeriod
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
from tgsis.errors import (
    AlreadyExistsError,
    DatabaseError,
    Error,
    FileFormatError,
    InstallationError,
    InUseError,
    InvalidGeometryError,
    InvalidInputError,
    InvalidNameError,
    InvalidPropertyError,
    LocalServerError,
    MissingPrivilegeError,
    NotFoundError,
    ObjectLockedError,
    ReadOnlyRevisionError,
    UnsolvedConflictsError,
    VersioningError,
)

try:
    __version__ = _package_version("tgsis")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = ExtensionSources.default().version

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
    # feature classes and features
    "FeatureClass",
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
    # time: surfaces at instants (model 2) and evolving surfaces (model 3)
    "SurfaceSeries",
    "EvolvingSurface",
    "TopologyPeriod",
    "add_instant",
    "delete_instant",
    "instants",
    "get_at",
    "surfaces_at",
    "features_at",
    "Period",
    "property_periods",
    "first_times",
    # errors
    "Error",
    "AlreadyExistsError",
    "DatabaseError",
    "FileFormatError",
    "InstallationError",
    "InUseError",
    "InvalidGeometryError",
    "InvalidInputError",
    "InvalidNameError",
    "InvalidPropertyError",
    "LocalServerError",
    "MissingPrivilegeError",
    "NotFoundError",
    "ObjectLockedError",
    "ReadOnlyRevisionError",
    "UnsolvedConflictsError",
    "VersioningError",
]
