"""Which functions of schema tgsis PUBLIC may execute: a rule test.

The rule (docs/security.md, "Internal functions"): an internal function of tgsis is not executable by PUBLIC. The
internals only SECURITY DEFINER code reaches are its owner's alone (``REVOKE ALL ... FROM PUBLIC``); those a
tgsis role reaches as itself, through a function it may call with its own rights (``tgsis.mesh_merge_regions``,
the Python client, the browser view), are granted to ``tgsis_reader``, which every tgsis role is a member of.

There is no single list of the public SQL API, so this test holds it: the functions PUBLIC may execute in an
installed database must be exactly those listed here. A new function is either revoked from PUBLIC (an internal)
or added here on purpose. The list has two parts: the functions the documentation names (a test below checks
that docs/*.md still names each), and internals still executable by PUBLIC, left so while each is reviewed on its
own (they run as the calling role on the write path: versioned views, their triggers, the invoker functions of
the API; revoking one unreviewed would refuse a writer). Nothing may be added to the second part.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import psycopg

Conn = psycopg.Connection[Any]

ROOT = Path(__file__).resolve().parent.parent

# named in docs/*.md (as `name`, `name(` or tgsis.name): the API users call, and functions the docs describe
_NAMED_IN_DOCS = frozenset(
    {
        "add_instant",
        "add_property",
        "add_to_model",
        "alter_class_table",
        "calling_role",
        "changed_objects",
        "check_class_write",
        "check_geometry",
        "check_key_type",
        "check_period_continuity",
        "check_registrable",
        "check_storage_call",
        "check_temporal_geometry",
        "check_unchanged",
        "checked_operator",
        "checked_time",
        "checkout_revision",
        "chunk_array_missing",
        "chunk_object_extent",
        "chunk_snapshot_guard",
        "claim_unversioned_geoid",
        "class_denied_geoids",
        "class_property_periods",
        "class_rights_filter",
        "close_object_rows",
        "compare_geometries",
        "compare_geometry_versions",
        "conflict_discards",
        "conflict_rows",
        "create_model",
        "create_revision_indexes",
        "create_version",
        "create_versioned_view",
        "cube_has_nan",
        "delete_geometry",
        "delete_instant",
        "delete_object_rows",
        "delete_period",
        "delete_stored_geometries",
        "delete_version",
        "diff_table",
        "diff_versions",
        "disable_versioning",
        "drop_feature_class",
        "drop_property",
        "enable_versioning",
        "enable_versioning_rel",
        "evolving_chunk_vertices",
        "evolving_frame",
        "evolving_instants",
        "evolving_satisfied",
        "ewkb_geometry",
        "ewkb_geometry_at",
        "exists_at",
        "feature_write_lock",
        "features_at",
        "fill_property_rows",
        "find_conflicts",
        "first_time",
        "gap_tolerance",
        "geometries_in_box",
        "geometry_changes",
        "geometry_instants",
        "geometry_version_changes",
        "get_revisions",
        "get_viewing_revision",
        "get_working_revision",
        "gmap_alpha_array",
        "gmap_at",
        "gmap_cells",
        "gmap_check",
        "gmap_chunk_arrays_sql",
        "gmap_conditions_by_arrays",
        "gmap_conditions_by_rows",
        "gmap_conditions_hold",
        "gmap_points_at",
        "gmap_property_at",
        "gmap_side_gap",
        "goto_revision",
        "goto_version",
        "grant_version",
        "has_version_privilege",
        "insert_chunk_rows",
        "insert_postgis_feature",
        "instant_at",
        "instant_periods",
        "linear_satisfied",
        "lock_for_region_merge",
        "lock_objects",
        "md_cells",
        "md_check",
        "md_in_box",
        "md_vertices_in_box",
        "merge_version",
        "mesh_changes",
        "mesh_from_postgis",
        "mesh_merge_regions",
        "model_objects",
        "modeltime_range",
        "new_geometry",
        "no_model_rule",
        "object_chunks_stage",
        "object_class_lock_key",
        "object_fingerprint",
        "object_key_text",
        "object_lock_key",
        "object_lock_limit",
        "object_write_lock",
        "or_list",
        "period_gaps",
        "plain_write_check",
        "point_chunk_box",
        "postgis_rows",
        "postgis_schema",
        "property_at",
        "property_periods",
        "record_changed_objects",
        "record_conflict_regions",
        "refresh_geometry",
        "refresh_version",
        "register_feature_class",
        "remove_from_model",
        "rename_property",
        "resolve_all_regions",
        "resolve_conflict",
        "resolve_region",
        "restore_storage_runner",
        "revision_set",
        "revoke_version",
        "rows_at",
        "satisfies",
        "save_revision",
        "set_version_owner",
        "set_version_validity",
        "shell_quote",
        "storage_rows_check",
        "storage_run",
        "storage_table",
        "stored_in_chunks",
        "storage_write_check",
        "surface_side_gap",
        "surfaces_at",
        "swap_object_chunks",
        "table_fingerprint",
        "time_key_columns",
        "timemultirange",
        "timerange",
        "triangles_at",
        "unlock_objects",
        "version",
        "version_believed_at",
        "version_chain",
        "version_id",
        "vertex",
        "vertices",
        "vertices_at",
        "visible_versions",
        "write_object_rows",
        "write_revision",
    }
)

# internals still executable by PUBLIC, each run as the calling role on a write or read path (trigger functions
# and their checks, view sources, the helpers of invoker API functions): to be revoked one by one with a test of
# the role that reaches it; never add to this list
_INTERNALS_STILL_PUBLIC = frozenset(
    {
        "canonical_object_keys",
        "catalog_row",
        "cell_labels",
        "check_gmap_geometry",
        "check_key_canonical",
        "check_md_geometry",
        "check_object_class",
        "check_objects_unlocked",
        "check_role",
        "check_static_geometry",
        "check_version_name",
        "check_writable_revision",
        "checked_convention",
        "checked_objects",
        "checked_question",
        "class_for_change",
        "class_of_geoid",
        "class_property",
        "class_storage",
        "comment_property_columns",
        "comment_time_key_columns",
        "comparable_geometry",
        "copy_object_match_sql",
        "create_change_trigger",
        "create_class_view",
        "create_storage_runner",
        "create_versioning_queue",
        "create_versioning_trigger",
        "crossing_time",
        "disable_versioning_rel",
        "evolving_extent",
        "feature_of_class",
        "feature_srid",
        "forget_unversioned",
        "geometry_kind_check",
        "get_working_version",
        "gmap_conditions",
        "gmap_dart_tests",
        "gmap_edges_at",
        "gmap_extent",
        "gmap_frame",
        "holds_version_privilege",
        "insert_property_rows",
        "instants_extent",
        "invalid_period",
        "is_version_owner",
        "md_extent",
        "md_query_box",
        "model_id",
        "model_tables_of",
        "object_key_kind",
        "object_key_sql",
        "object_key_text_sql",
        "object_key_type",
        "oriented_cell_key",
        "own_working_revisions",
        "period_gap_place",
        "point_segment_distance",
        "point_triangle_distance",
        "property_columns",
        "property_rows_missing",
        "record_inserted_objects",
        "require_read_committed",
        "require_storage",
        "require_version_owner",
        "require_version_privilege",
        "resolve_table",
        "restore_dropped_constraints",
        "same_row_sql",
        "simplex_table",
        "static_extent",
        "storage_execute",
        "storage_runner_source",
        "temporal_geometry",
        "timerange_bounds_ok",
        "unversioned_revision",
        "version_class_tables",
        "version_privilege_list",
        "versioned_table",
        "versioned_view_source",
        "versioning_trigger_source",
        "view_write_check",
        "visible_object_keys",
    }
)

# the merge's internals (issue 39): SECURITY DEFINER merge, refresh, find_conflicts and resolve functions reach
# them as their owner; those a tgsis role reaches as itself are granted to tgsis_reader
_MERGE_INTERNALS = {
    "tgsis.check_no_unsolved_conflicts(text,text)": False,
    "tgsis.current_conflicts(integer)": True,  # the Python merge and the browser view, as the caller
    "tgsis.merge_ids_text(text[])": False,
    "tgsis.merge_mesh_by_region(text,text,bigint)": False,
    "tgsis.merge_mesh_validity(text,integer,text,text,bigint,integer[],text,text)": False,
    "tgsis.merge_number_text(double precision)": False,
    "tgsis.merge_regions_in_sql(text,text,boolean)": False,
    "tgsis.notice_discards(text,text,text,text)": False,
    "tgsis.mesh_merge_work(text,bigint,double precision,double precision)": True,  # run by tgsis.mesh_merge_regions, as its caller
    "tgsis.region_merge_refusal(text,bigint)": True,  # asked by tgsis.mesh_merge_work
    "tgsis.require_merge_privileges(text,text,boolean)": False,
    "tgsis.slice_only_edits(text,bigint,text)": True,  # docs/versioning.md shows it to a tgsis role
    "tgsis.store_mesh_regions(text,text)": False,
}


def _public_functions(conn: Conn) -> set[str]:
    rows = conn.execute(
        "SELECT DISTINCT p.proname FROM pg_proc p"
        " WHERE p.pronamespace = 'tgsis'::regnamespace AND p.prokind <> 'a'"
        "   AND has_function_privilege('public', p.oid, 'EXECUTE')"
    ).fetchall()
    return {str(name) for (name,) in rows}


def test_the_functions_public_may_execute_are_exactly_the_listed_ones(conn: Conn) -> None:
    """Fails naming a function PUBLIC may execute that is not listed (an internal to revoke, or an API function to
    list) and a listed one no longer PUBLIC (take it off the list)."""
    public = _public_functions(conn)
    listed = _NAMED_IN_DOCS | _INTERNALS_STILL_PUBLIC
    assert not _NAMED_IN_DOCS & _INTERNALS_STILL_PUBLIC
    assert sorted(public - listed) == [], "executable by PUBLIC but not listed: revoke it (an internal) or list it"
    assert sorted(listed - public) == [], "listed but not executable by PUBLIC: take it off the list"


def test_the_functions_listed_as_named_in_the_docs_are_named_there() -> None:
    text = "\n".join(path.read_text(encoding="utf-8") for path in sorted((ROOT / "docs").glob("*.md")))
    text += (ROOT / "README.md").read_text(encoding="utf-8")
    missing = [name for name in sorted(_NAMED_IN_DOCS) if not re.search(rf"(tgsis\.|`){name}(\(|`)", text)]
    assert missing == [], "listed as named in the docs, named nowhere there: move to the revoked internals"


def test_the_merge_internals_are_not_public_and_the_tgsis_roles_run_theirs(conn: Conn) -> None:
    """slicereview found them executable by PUBLIC (issue 39); the same in both install routes (test_upgrade
    compares the grants of CREATE EXTENSION with the upgrade's)."""
    for signature, reader in _MERGE_INTERNALS.items():
        row = conn.execute(
            "SELECT has_function_privilege('public', %s::regprocedure, 'EXECUTE'),"
            " has_function_privilege('tgsis_reader', %s::regprocedure, 'EXECUTE')",
            (signature, signature),
        ).fetchone()
        assert row == (False, reader), signature
