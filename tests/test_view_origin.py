"""The browser view refuses what a page of another site makes a browser send (issue 36, point 9).

The view's only state is the version a browser chose (a cookie set by
``POST /session``). A page of another origin — another site, or another port
of this machine — must not move a user to another version with a form that
submits itself: every request other than GET and HEAD must carry an
``Origin`` (else a ``Referer``) naming the view itself, or is refused with 403
and a message saying why. Requests naming another host (a name of an
attacker's that resolves to 127.0.0.1: DNS rebinding) are refused with 400.

Covered: every route and method the application declares (so a future POST
cannot skip the check), curl-like requests with a forged, foreign, ``null``
or missing Origin, and, in headless Chromium, a form served from another
origin (another port of 127.0.0.1, and localhost) that submits itself to the
view: refused, and the version stays; the view's own buttons still choose
the version; a page under a rebinding name gets nothing.
"""

from __future__ import annotations

import asyncio
import http.client
import http.server
import threading
import urllib.parse
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import pytest
from starlette.routing import Mount, Route

from tests.view_helpers import CHROMIUM, CHROMIUM_ARGS, ViewData, chromium, fill_view_database, running_view
from tgsis.testing import TestServer
from tgsis.view.app import VERSION_COOKIE, RequestGuard, ViewConfig, create_app

UNSAFE = ("POST", "PUT", "PATCH", "DELETE")


@pytest.fixture(scope="module")
def view(pg: TestServer, template_db: str) -> Iterator[tuple[str, ViewData]]:
    with pg.database("tgsis_view_origin", template_db) as (_, dsn):
        data = fill_view_database(dsn)
        with running_view(dsn) as url:
            yield url, data


def _send(
    url: str, method: str, path: str, headers: dict[str, str], body: bytes = b""
) -> tuple[int, str, http.client.HTTPResponse]:
    """A raw request (the headers exactly as given, as curl sends them): status, body, response."""
    parts = urllib.parse.urlsplit(url)
    conn = http.client.HTTPConnection(parts.hostname or "", parts.port, timeout=60)
    try:
        conn.request(method, path, body=body, headers=headers)
        response = conn.getresponse()
        return response.status, response.read().decode("utf-8", "replace"), response
    finally:
        conn.close()


def _choose(url: str, version: str, headers: dict[str, str]) -> tuple[int, str, str | None]:
    """POST /session version=VERSION with ``headers``: status, body, the Set-Cookie header."""
    form = urllib.parse.urlencode({"version": version}).encode()
    status, body, response = _send(
        url, "POST", "/session", {"Content-Type": "application/x-www-form-urlencoded", **headers}, form
    )
    return status, body, response.getheader("Set-Cookie")


def _routes() -> list[tuple[str, set[str]]]:
    """Every route of the application with its methods (a path parameter filled with 1)."""
    app = create_app(ViewConfig("dbname=unused"))
    routes = []
    for route in app.routes:
        if isinstance(route, Route):
            routes.append((route.path.replace("{id}", "1"), set(route.methods or ())))
        elif isinstance(route, Mount):
            routes.append((route.path + "/vendor/three/LICENSE", {"GET", "HEAD"}))
        else:  # pragma: no cover - a new kind of route must be added here
            raise AssertionError(f"unknown route {route!r}")
    return routes


def test_the_application_declares_the_routes_this_test_knows() -> None:
    # a new route with a method other than GET joins the enumeration below by itself; this says which exist
    unsafe = {path: methods - {"GET", "HEAD"} for path, methods in _routes() if methods - {"GET", "HEAD"}}
    assert unsafe == {"/session": {"POST"}}


@pytest.mark.parametrize(
    ("path", "method"),
    sorted({(path, m) for path, methods in _routes() for m in (methods - {"GET", "HEAD"}) | set(UNSAFE)}),
)
def test_every_route_refuses_a_foreign_or_missing_origin(view: tuple[str, ViewData], path: str, method: str) -> None:
    url, _ = view
    own = url  # http://127.0.0.1:PORT
    for headers in (
        {"Origin": "http://evil.example"},
        {},
        {"Origin": "null"},
        {"Referer": "http://evil.example/attack.html"},
    ):
        status, body, _ = _send(url, method, path, headers, b"version=edit")
        assert status == 403, (method, path, headers, status, body)
        assert "refused" in body and own in body, body
    # from the view's own origin, the same request reaches the route (a method it has not: 405, not 403)
    status, _, _ = _send(url, method, path, {"Origin": own}, b"version=DEFAULT")
    assert status != 403, (method, path, status)


def test_curl_like_requests_to_choose_the_version(view: tuple[str, ViewData]) -> None:
    url, _ = view
    port = urllib.parse.urlsplit(url).port
    assert port is not None
    refused = {
        "no Origin nor Referer": {},
        "a forged Origin": {"Origin": "http://evil.example"},
        "another port of this machine": {"Origin": f"http://127.0.0.1:{port + 1 if port < 65535 else 1}"},
        "another name of this machine": {"Origin": f"http://localhost:{port}"},
        "another scheme": {"Origin": f"https://127.0.0.1:{port}"},
        "an opaque origin": {"Origin": "null"},
        "a foreign Referer": {"Referer": "http://evil.example/page"},
        "a foreign Origin with the view's Referer": {"Origin": "http://evil.example", "Referer": f"{url}/versions"},
        "a malformed Origin": {"Origin": "http://127.0.0.1:notaport"},
    }
    for why, headers in refused.items():
        status, body, cookie = _choose(url, "edit", headers)
        assert status == 403, (why, status, body)
        assert cookie is None, why
        assert body.startswith("403 Forbidden: tgsis view refused POST /session"), body
        assert f"only from its own pages ({url})" in body, body
    status, body, _ = _choose(url, "edit", {})
    assert "names neither Origin nor Referer" in body
    status, body, _ = _choose(url, "edit", {"Origin": "http://evil.example"})
    assert "comes from http://evil.example" in body
    for headers in ({"Origin": url}, {"Referer": f"{url}/versions?x=1"}, {"Origin": url.replace("http:", "HTTP:")}):
        status, body, cookie = _choose(url, "edit", headers)
        assert status == 303, (headers, status, body)
        assert cookie is not None and cookie.startswith(f"{VERSION_COOKIE}=edit"), cookie


def test_a_request_naming_another_host_is_refused_whatever_its_method(view: tuple[str, ViewData]) -> None:
    # DNS rebinding: a name of the attacker's resolved to 127.0.0.1 reaches the socket, not the view
    url, _ = view
    for method, path in (("GET", "/classes"), ("POST", "/session")):
        status, body, _ = _send(url, method, path, {"Host": "rebind.example:80", "Origin": "http://rebind.example"})
        assert status == 400 and "rebind.example" in body, (method, status, body)
    status, body, _ = _send(url, "GET", "/classes", {"Host": "[::1"})  # a malformed Host header
    assert status == 400


def test_a_view_on_an_ipv6_address_answers_its_own_pages(
    view: tuple[str, ViewData], pg: TestServer, template_db: str
) -> None:
    # tgsis view --host ::1: the Host header is [::1]:PORT (Starlette's TrustedHostMiddleware refused it all)
    with pg.database("tgsis_view_v6", template_db) as (_, dsn), running_view(dsn, host="::1") as url:
        assert url.startswith("http://[::1]:")
        status, body, _ = _send(url, "GET", "/versions", {})
        assert status == 200, body
        status, body, cookie = _choose(url, "DEFAULT", {"Origin": url})
        assert status == 303 and cookie is not None, body
        status, body, _ = _choose(url, "DEFAULT", {"Origin": url.replace("[::1]", "127.0.0.1")})
        assert status == 403, body


def test_a_websocket_is_checked_as_a_post() -> None:
    # no route is a websocket today; one added later gets the same check (browsers send Origin on the handshake)
    reached: list[str] = []

    async def inner(scope: Any, receive: Any, send: Any) -> None:
        reached.append(scope["path"])

    guard = RequestGuard(inner, ["127.0.0.1", "localhost"])

    def connect(origin: str | None, host: str = "127.0.0.1:8765") -> list[Any]:
        sent: list[Any] = []

        async def receive() -> Any:
            return {"type": "websocket.connect"}

        async def send(message: Any) -> None:
            sent.append(message)

        headers = [(b"host", host.encode())] + ([(b"origin", origin.encode())] if origin else [])
        asyncio.run(guard({"type": "websocket", "path": "/ws", "headers": headers, "scheme": "ws"}, receive, send))
        return sent

    for origin in ("http://evil.example", None, "http://127.0.0.1:8766"):
        assert [m["type"] for m in connect(origin)] == ["websocket.close"], origin
        assert connect(origin)[0]["code"] == 1008
    assert [m["code"] for m in connect("http://127.0.0.1:8765", host="rebind.example:8765")] == [1008]
    assert reached == []
    assert connect("http://127.0.0.1:8765") == [] and reached == ["/ws"]


# --------------------------------------------------------------------------- in a browser


class _AttackPage(http.server.BaseHTTPRequestHandler):
    """Serves ``/``, a page whose form posts itself to the view, and ``/frame``, the view's versions page in a frame."""

    def do_GET(self) -> None:  # noqa: N802 (the name http.server calls)
        target = self.server.target  # type: ignore[attr-defined]
        if self.path == "/frame":  # clickjacking: the view's own button under a decoy, in a frame
            body = f"<!doctype html><html><body><iframe id=v src='{target}/versions'></iframe></body></html>".encode()
        else:
            body = (
                f"<!doctype html><html><body><form id=f method=post action='{target}/session'>"
                "<input type=hidden name=version value=edit></form>"
                "<script>document.getElementById('f').submit()</script></body></html>"
            ).encode()
        self.send_response(200)
        self.send_header("Content-Type", "text/html; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, format: str, *args: Any) -> None:
        pass


@contextmanager
def _attacker(target: str) -> Iterator[int]:
    """Another web server on another port of 127.0.0.1 serving the attack page; yields its port."""
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _AttackPage)
    server.target = target  # type: ignore[attr-defined]
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield server.server_address[1]
    finally:
        server.shutdown()
        server.server_close()
        thread.join(10)


@pytest.mark.parametrize("attacker_host", ["127.0.0.1", "localhost"])
def test_a_form_of_another_origin_cannot_move_the_browser_to_another_version(
    view: tuple[str, ViewData], attacker_host: str
) -> None:
    url, _ = view
    with _attacker(url) as port, chromium() as browser:
        context = browser.new_context()
        page = context.new_page()
        page.goto(f"{url}/versions")  # the user works in the view (DEFAULT)
        assert page.text_content("#current") == "DEFAULT"
        with page.expect_response(f"{url}/session") as posted:
            page.goto(f"http://{attacker_host}:{port}/")  # ...and opens another site's page
        response = posted.value
        assert response.request.method == "POST"
        assert response.status == 403
        assert "refused POST /session" in response.text()
        assert not [c for c in context.cookies() if c["name"] == VERSION_COOKIE]
        page.goto(f"{url}/versions")
        assert page.text_content("#current") == "DEFAULT"
        # the view's own page still chooses the version
        page.click("#versions tr[data-version=edit] button.choose")
        assert page.text_content("#current") == "edit"
        page.goto(f"{url}/versions")
        assert page.text_content("#current") == "edit"
        context.close()


def test_a_page_of_another_site_cannot_frame_the_view(view: tuple[str, ViewData]) -> None:
    # the view's own form inside a frame would carry the view's Origin: the view refuses to be framed
    url, _ = view
    status, _, response = _send(url, "GET", "/versions", {})
    assert status == 200
    assert response.getheader("X-Frame-Options") == "DENY"
    assert "frame-ancestors 'none'" in (response.getheader("Content-Security-Policy") or "")
    with _attacker(url) as port, chromium() as browser:
        context = browser.new_context()
        page = context.new_page()
        with page.expect_response(f"{url}/versions") as framed:
            page.goto(f"http://127.0.0.1:{port}/frame")
        assert framed.value.status == 200  # served, and not shown
        page.wait_for_timeout(500)
        frame = page.frame_locator("#v")
        assert frame.locator("#versions").count() == 0, "the view's page is shown inside another site's page"
        context.close()


def test_a_page_under_a_rebinding_name_gets_nothing(view: tuple[str, ViewData]) -> None:
    url, _ = view
    port = urllib.parse.urlsplit(url).port
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        # the browser resolves the attacker's name to 127.0.0.1, as a rebinding DNS server would make it
        browser = playwright.chromium.launch(
            executable_path=CHROMIUM, args=[*CHROMIUM_ARGS, "--host-resolver-rules=MAP rebind.example 127.0.0.1"]
        )
        try:
            page = browser.new_page()
            response = page.goto(f"http://rebind.example:{port}/versions")
            assert response is not None and response.status == 400
            assert "rebind.example" in (page.text_content("body") or "")
        finally:
            browser.close()
