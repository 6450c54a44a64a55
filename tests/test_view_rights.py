"""The browser view shows what the user's role may read, and writes nothing unless started writable (issue 21).

The view connects with the user's own conninfo: a tgsis_reader whose
class was revoked sees that class as not readable, none of its features,
and gets 404 for them where the owner gets them; every transaction is
read-only (``default_transaction_read_only``) unless ``writable``; requests
naming another host are refused (a page of another site cannot reach the
view under a name of its own).
"""

from __future__ import annotations

import urllib.error
import urllib.request
from collections.abc import Iterator
from typing import Any

import psycopg
import pytest
from psycopg.conninfo import make_conninfo
from starlette.requests import Request

from tests.roles import login_roles
from tests.view_helpers import ViewData, chromium, fill_view_database, get, running_view
from tgsis.errors import Error
from tgsis.testing import TestServer
from tgsis.view.app import View, ViewConfig


@pytest.fixture(scope="module")
def database(pg: TestServer, template_db: str) -> Iterator[tuple[str, ViewData]]:
    with pg.database("tgsis_view_rights", template_db) as (_, dsn):
        yield dsn, fill_view_database(dsn)


def _ids(page: Any) -> list[int]:
    return [int(i) for i in page.locator("#features tbody tr").evaluate_all("rows => rows.map(r => r.dataset.id)")]


def test_a_role_with_fewer_rights_sees_less(database: tuple[str, ViewData]) -> None:
    dsn, data = database
    with (
        login_roles(dsn, {"reader": "tgsis_reader"}) as roles,
        running_view(make_conninfo(dsn, user=roles.name("reader"))) as reader_url,
        running_view(dsn) as owner_url,
        chromium() as browser,
    ):
        page = browser.new_page()
        page.goto(f"{owner_url}/classes")
        assert data.hidden in _ids(page)
        page.goto(f"{reader_url}/classes")
        seen = _ids(page)
        assert data.hidden not in seen and data.top in seen
        assert page.locator("#classes tr[data-class=secret] td.count").text_content() == "not readable by this role"
        assert page.locator("#classes tr[data-class=horizons] td.count").text_content() == "3"
        assert page.goto(f"{reader_url}/scene?ids={data.hidden}").status == 404
        assert page.goto(f"{owner_url}/scene?ids={data.hidden}").status == 200
        status, body, _ = get(f"{reader_url}/api/mesh/{data.hidden}")
        assert status == 404 and b"no feature" in body
        assert get(f"{owner_url}/api/mesh/{data.hidden}")[0] == 200
        assert get(f"{reader_url}/api/mesh/{data.top}")[0] == 200
        page.close()


def _request(cookie: str | None = None) -> Request:
    headers = [(b"cookie", f"tgsis_version={cookie}".encode())] if cookie else []
    return Request({"type": "http", "method": "GET", "path": "/", "headers": headers, "query_string": b""})


@pytest.mark.parametrize("writable", [False, True])
def test_transactions_are_read_only_unless_writable(database: tuple[str, ViewData], writable: bool) -> None:
    dsn, data = database
    view = View(ViewConfig(dsn, writable=writable))
    statement = "UPDATE horizons SET unit = 'Z' WHERE _geoid = %s"
    if writable:
        with view.session(_request()) as conn:
            conn.execute(statement, (data.quoted,))
            assert conn.execute("SELECT unit FROM horizons WHERE _geoid = %s", (data.quoted,)).fetchone() == ("Z",)
            raise psycopg.Rollback()  # leave the database as it was
    else:
        with pytest.raises(Error, match="read-only transaction"):
            with view.session(_request("edit")) as conn:
                conn.execute(statement, (data.quoted,))
    with psycopg.connect(dsn) as conn:
        assert conn.execute("SELECT unit FROM horizons WHERE _geoid = %s", (data.quoted,)).fetchone() == ("C",)


def test_the_version_shown_until_the_browser_chooses_one(database: tuple[str, ViewData]) -> None:
    # tgsis --in edit view: the server's default; a browser's choice (its cookie) wins
    dsn, data = database
    with running_view(dsn, default_version="edit") as url:
        status, body, _ = get(f"{url}/classes")
        assert status == 200 and b"In version <b>edit</b>" in body
        request = urllib.request.Request(f"{url}/classes", headers={"Cookie": "tgsis_version=DEFAULT"})
        with urllib.request.urlopen(request, timeout=30) as response:
            assert b"In version <b>DEFAULT</b>" in response.read()


def test_a_chosen_version_deleted_since_leaves_a_way_back(database: tuple[str, ViewData]) -> None:
    # the browser's cookie names a version that does not exist (any more): every page says so, and offers DEFAULT
    dsn, _ = database
    with running_view(dsn) as url, chromium() as browser:
        context = browser.new_context()
        context.add_cookies([{"name": "tgsis_version", "value": "gone'", "url": url}])
        page = context.new_page()
        assert page.goto(f"{url}/classes").status == 404
        assert "gone''" in page.text_content("#error-message")
        page.click("#back-to-default")
        assert page.url.endswith("/versions") and page.text_content("#current") == "DEFAULT"
        assert page.goto(f"{url}/classes").status == 200
        context.close()


def test_a_request_for_another_host_is_refused(database: tuple[str, ViewData]) -> None:
    dsn, _ = database
    with running_view(dsn) as url:
        request = urllib.request.Request(f"{url}/classes", headers={"Host": "evil.example"})
        try:
            urllib.request.urlopen(request, timeout=30)
            status = 200
        except urllib.error.HTTPError as exc:
            status = exc.code
        assert status == 400
        assert get(f"{url}/classes")[0] == 200
