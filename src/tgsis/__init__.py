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

import ast
import functools
import importlib
import logging
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _package_version
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tgsis.compare import MeshDiff, MeshIndex, compare_meshes
from tgsis.convert import as_mesh
from tgsis.datamodels import DataModel, TimeModel, data_models
from tgsis.errors import (
    AlreadyExistsError,
    CheckoutConflictError,
    ConcurrentChangeError,
    ConcurrentReadError,
    DatabaseError,
    DiscontinuousPeriodsError,
    Error,
    FileFormatError,
    InstallationError,
    InUseError,
    InvalidGeometryError,
    InvalidGMapError,
    InvalidInputError,
    InvalidMergeError,
    InvalidNameError,
    InvalidPropertyError,
    LocalServerError,
    MissingPrivilegeError,
    NotFoundError,
    NotVersionedError,
    ObjectLockedError,
    PeriodTopologyError,
    PolygonsSplitWarning,
    ReadOnlyRevisionError,
    RegionSolutionError,
    SkippedObjectWarning,
    UnknownDataModelError,
    UnsolvedConflictsError,
    UnsupportedViewStatementError,
    VersioningError,
)
from tgsis.gmaps import EvolvingGMap, GMap, GMapPeriod, GMapReport
from tgsis.gmaps import extrude as extrude_gmap
from tgsis.gmaps import slice as slice_gmap
from tgsis.merge3 import (
    MergeRegion,
    MeshMerge,
    MeshState,
    RegionDiscard,
    ResolvedMerge,
    apply_solutions,
    three_way_merge,
)
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
from tgsis.temporal import EvolvingSurface, Period, SurfaceSeries, TopologyPeriod, WrittenSeries, write_series_pvd

if TYPE_CHECKING:  # the database layer, for type checkers; at run time it loads on first use (below)
    from tgsis.db import (
        ExtensionSources,
        InstallationStatus,
        InstalledVersion,
        InstallResult,
        LocalServer,
        connect,
        find_binaries,
        install,
        installation_status,
        installed_version,
        partition_model_storage,
        uninstall,
    )
    from tgsis.db.adapters import Box, register_types
    from tgsis.db.checkin import (
        CheckinResult,
        Checkout,
        CheckoutToken,
        SaveResult,
        checkin,
        checkout,
        save_feature,
    )
    from tgsis.db.classes import add_property, drop_property, fill_property_rows, rename_property
    from tgsis.db.compare import GeometryChanges, compare_stored, compare_versions
    from tgsis.db.evolving import append_period, delete_period, fetch_evolving
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
        fetch_object,
        get_feature_class,
        insert_feature,
        list_feature_classes,
    )
    from tgsis.db.gmaps import GMapProblem, fetch_gmap, gmap_at, gmap_cells, gmap_check, insert_gmap
    from tgsis.db.instants import add_instant, delete_instant, fetch_series
    from tgsis.db.merging import (
        MergedObject,
        MergeResult,
        export_conflict,
        merge_regions_json,
        merge_version,
        object_merge,
        refresh_version,
    )
    from tgsis.db.modelsets import (
        Model,
        ModelObject,
        add_to_model,
        create_model,
        list_models,
        model_objects,
        remove_from_model,
    )
    from tgsis.db.multidim import fetch_md_gmap, md_in_box, md_vertices_in_box
    from tgsis.db.postgis import create_postgis_view, enable_postgis, fetch_ewkb, insert_wkb_feature, postgis_enabled
    from tgsis.db.regions import (
        ConflictRegion,
        ObjectResolution,
        RegionResolution,
        SideDiscard,
        find_conflicts,
        resolve_all_regions,
        resolve_conflict,
        resolve_region,
    )
    from tgsis.db.temporal import (
        class_property_periods,
        export_series,
        features_at,
        first_times,
        frames_at,
        get_at,
        instants,
        lifespan,
        property_periods,
        surfaces_at,
    )
    from tgsis.db.versions import (
        Compressed,
        Conflict,
        Difference,
        Discard,
        ObjectLock,
        Version,
        VersionedTable,
        VersionGrant,
        at_revision,
        compress_versions,
        conflict_discards,
        conflict_rows,
        create_version,
        delete_version,
        diff_table,
        diff_versions,
        disable_feature_versioning,
        disable_versioning,
        enable_feature_versioning,
        enable_versioning,
        goto_revision,
        goto_version,
        grant_version,
        has_version_privilege,
        in_version,
        list_versions,
        lock_objects,
        object_locks,
        revisions,
        revoke_version,
        save_revision,
        set_version_owner,
        set_version_validity,
        unlock_objects,
        version_believed_at,
        version_chain,
        version_graph,
        version_privileges,
        versioned_tables,
        viewing_revision,
        working_revision,
        working_version,
    )
    from tgsis.interpolation.deposition import Contact, Deposition, Stacking, deposit, drape, keep_above
    from tgsis.postgis import mesh_from_wkb, mesh_to_ewkb

# The database layer (and psycopg) is imported on first use of one of its
# names, so that the numpy modules (tgsis.mesh, compare, edits, temporal,
# interpolation, formats) load without it (tests/test_pure_imports.py). Which
# module a name of __all__ comes from is read from the ``__all__`` of these
# modules (without importing them): a name added there and to __all__ below
# (and to the TYPE_CHECKING block above, tests/test_public_api.py) needs no
# other list. The first module that lists a name gives it.
_LAZY_MODULES = (
    "tgsis.db",
    "tgsis.db.merging",  # before versions: the merges by region are the public merge_version, refresh_version
    "tgsis.db.regions",  # before versions: its region-aware find_conflicts is the public one
    "tgsis.db.versions",
    "tgsis.db.features",
    "tgsis.db.classes",
    "tgsis.db.checkin",
    "tgsis.db.adapters",
    "tgsis.db.compare",
    "tgsis.db.instants",
    "tgsis.db.evolving",
    "tgsis.db.temporal",
    "tgsis.db.postgis",
    "tgsis.postgis",
    "tgsis.db.multidim",
    "tgsis.db.gmaps",
    "tgsis.db.modelsets",
    # numpy, no database, but with the interpolation's scipy: loaded on first use too
    "tgsis.interpolation.deposition",
)


def _module_all(module: str) -> list[str]:
    """The ``__all__`` of a module of this package, read from its source (a literal list) without importing it."""
    relative = Path(*module.split(".")[1:])
    for path in (_HERE / relative.with_suffix(".py"), _HERE / relative / "__init__.py"):
        if path.is_file():
            for node in ast.parse(path.read_text(encoding="utf-8"), str(path)).body:
                if isinstance(node, ast.Assign) and any(
                    isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
                ):
                    return list(ast.literal_eval(node.value))
    return list(importlib.import_module(module).__all__)  # no source beside it (compiled only): import it


@functools.cache
def _lazy_table() -> dict[str, str]:
    """Public name -> the module it is imported from on first use."""
    public = set(__all__)
    table: dict[str, str] = {}
    for module in _LAZY_MODULES:
        for name in _module_all(module):
            if name in public:
                table.setdefault(name, module)
    return table


def _source_tree_version() -> str:
    """The version of a source tree that is not installed: the extension's (sql/tgsis.control)."""
    from tgsis.db.sqlsource import ExtensionSources

    return ExtensionSources.default().version


def __getattr__(name: str) -> Any:
    """The database layer's public names, imported when first asked for (PEP 562)."""
    if name == "__version__":  # only when not installed (else set below): it reads the extension's sources
        value: Any = _source_tree_version()
    else:
        module = _lazy_table().get(name) if name in __all__ else None
        if module is None:
            raise AttributeError(f"module 'tgsis' has no attribute {name!r}")
        value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


_HERE = Path(__file__).parent

try:
    __version__ = _package_version("tgsis")
except PackageNotFoundError:  # a source tree that is not installed: on first use (the database layer reads it)
    pass

logging.getLogger("tgsis").addHandler(logging.NullHandler())

__all__ = [
    "__version__",
    # connections and installation
    "connect",
    "install",
    "installation_status",
    "installed_version",
    "partition_model_storage",
    "uninstall",
    "InstallResult",
    "InstallationStatus",
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
    "version_graph",
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
    "resolve_region",
    "resolve_all_regions",
    "ConflictRegion",
    "RegionResolution",
    "ObjectResolution",
    "SideDiscard",
    "conflict_rows",
    "Discard",
    "conflict_discards",
    "merge_version",
    "object_merge",
    "MergeResult",
    "MergedObject",
    "export_conflict",
    "merge_regions_json",
    "refresh_version",
    "Difference",
    "diff_versions",
    "diff_table",
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
    # three-way merge of one mesh's edits per region (numpy, no database; docs/merge.md)
    "MeshState",
    "MergeRegion",
    "MeshMerge",
    "RegionDiscard",
    "ResolvedMerge",
    "three_way_merge",
    "apply_solutions",
    # generalized maps, models 4 and 5 (numpy, no database; more in tgsis.gmaps)
    "GMap",
    "GMapReport",
    "GMapPeriod",
    "EvolvingGMap",
    "extrude_gmap",
    "slice_gmap",
    # the data models (tgsis.data_models)
    "DataModel",
    "TimeModel",
    "data_models",
    # G-maps in the database (model 4)
    "insert_gmap",
    "fetch_gmap",
    "gmap_at",
    "gmap_cells",
    "gmap_check",
    "GMapProblem",
    "fetch_md_gmap",
    "md_in_box",
    # models as sets of objects
    "Model",
    "ModelObject",
    "create_model",
    "register_types",
    "Box",
    "add_to_model",
    "remove_from_model",
    "model_objects",
    "list_models",
    "md_vertices_in_box",
    # deposition: a unit growing from the surface beneath, younger tops kept above older ones (numpy, no database)
    "deposit",
    "Deposition",
    "drape",
    "keep_above",
    "Stacking",
    "Contact",
    # feature classes and features
    "FeatureClass",
    "Property",
    "Feature",
    "create_feature_class",
    "get_feature_class",
    "list_feature_classes",
    "drop_feature_class",
    "add_property",
    "rename_property",
    "drop_property",
    "fill_property_rows",
    "insert_feature",
    "fetch_feature",
    "fetch_features",
    "fetch_object",
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
    # PostGIS (docs/postgis.md)
    "create_postgis_view",
    "enable_postgis",
    "fetch_ewkb",
    "insert_wkb_feature",
    "postgis_enabled",
    "mesh_from_wkb",
    "mesh_to_ewkb",
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
    "ConcurrentReadError",
    "DatabaseError",
    "FileFormatError",
    "SkippedObjectWarning",
    "PolygonsSplitWarning",
    "InstallationError",
    "InUseError",
    "UnknownDataModelError",
    "DiscontinuousPeriodsError",
    "InvalidGeometryError",
    "InvalidGMapError",
    "InvalidInputError",
    "InvalidMergeError",
    "InvalidNameError",
    "InvalidPropertyError",
    "LocalServerError",
    "MissingPrivilegeError",
    "NotFoundError",
    "NotVersionedError",
    "UnsupportedViewStatementError",
    "RegionSolutionError",
    "PeriodTopologyError",
    "ObjectLockedError",
    "CheckoutConflictError",
    "ReadOnlyRevisionError",
    "UnsolvedConflictsError",
    "VersioningError",
]
