"""Hostile cases of the merges that write by region and of the region store (issue 39 review)."""

from __future__ import annotations

import logging
from typing import Any

import psycopg
import pytest

import tgsis
from tests.merge_data import make_fault, move

Conn = psycopg.Connection[Any]


@pytest.fixture
def fault(conn: Conn) -> int:
    return make_fault(conn)


def _overlapping_edits(conn: Conn, fault: int) -> tgsis.ConflictRegion:
    """One conflicting region (vertex 66 moved differently on both sides), recorded; returned."""
    move(conn, "e1", fault, [64, 65, 66], (0.0, 0.0, 5.0))
    move(conn, "DEFAULT", fault, [66, 67], (0.0, 0.0, -4.0))
    conn.commit()
    (conflict,) = tgsis.find_conflicts(conn, "e1")
    conn.commit()
    (region,) = [r for r in conflict.regions if r.conflict]
    return region


def test_an_average_solution_is_named_average_in_what_it_discards(
    conn: Conn, fault: int, caplog: pytest.LogCaptureFixture
) -> None:
    region = _overlapping_edits(conn, fault)
    resolution = tgsis.resolve_region(conn, "e1", fault, region.region, "average")
    conn.commit()
    assert resolution.discards and {d.solution for d in resolution.discards} == {"average"}
    assert "manual" not in resolution.summary() and "average discards" in resolution.summary()
    with caplog.at_level(logging.WARNING, logger="tgsis.db.merging"):
        result = tgsis.merge_version(conn, "e1")
    (merged,) = result.objects
    assert merged.discards and {d.solution for d in merged.discards} == {"average"}
    warnings = [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]
    assert warnings and all("solved average" in w for w in warnings), warnings
