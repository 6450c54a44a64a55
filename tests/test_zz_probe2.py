from __future__ import annotations

import threading
import time
from typing import Any

import numpy as np
import psycopg
import pytest

import tgsis
from tests.test_sql_merge_solutions_hostile import _conflict, _replace
from tests.test_sql_merge_regions import MIDDLE


@pytest.fixture
def fault(conn: Any, fault_clone: int) -> int:
    return fault_clone


def test_probe_race(conn: Any, fault: int, db_dsn: str) -> None:
    index, merge = _conflict(conn, fault)
    tgsis.resolve_region(conn, "e1", fault, index, "average")
    conn.commit()
    b = psycopg.connect(db_dsn)
    xyz = merge.child.vertices.copy()
    xyz[np.isin(merge.child.vertex_ids, MIDDLE), 2] += 2.0
    from tgsis.db.regions import _sql_rows, state_to_npz
    m = _replace(merge.child, vertices=xyz)
    b.execute(
        "SELECT FROM tgsis.resolve_region('e1', 'feature', %s, %s, 'manual', %s, %s, %s::float8[], %s, %s,"
        " %s::text[], %s::float8[], %s::text[], %s::float8[])",
        (str(fault), index, state_to_npz(m), *_sql_rows(m)),
    )
    print("B IN TX", b.info.transaction_status)
    out: dict[str, Any] = {}

    def run() -> None:
        a = psycopg.connect(db_dsn)
        t0 = time.monotonic()
        try:
            out["rows"] = a.execute("SELECT tgsis.merge_version('e1')").fetchone()
            a.commit()
        except psycopg.Error as exc:
            out["err"] = (exc.sqlstate, str(exc)[:300])
        out["t"] = time.monotonic() - t0
        a.close()

    th = threading.Thread(target=run)
    th.start()
    time.sleep(3)
    print("WAITING", th.is_alive(), b.execute("SELECT pid, wait_event_type, wait_event, left(query, 60) FROM pg_stat_activity WHERE datname = current_database() AND state <> 'idle'").fetchall())
    b.commit()
    th.join(60)
    print("OUT", out)
    z = conn.execute("SELECT z FROM tgsis.vrtx_ver WHERE geoid = %s AND vrtxid = %s ORDER BY revision DESC LIMIT 1", (fault, int(MIDDLE[0]))).fetchone()
    print("Z", z, merge.child.vertices[np.searchsorted(merge.child.vertex_ids, MIDDLE[0])], merge.parent.vertices[np.searchsorted(merge.parent.vertex_ids, MIDDLE[0])])
    b.close()
