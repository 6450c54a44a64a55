"""The local PostgreSQL tgsis runs by itself: binaries, clusters, leases."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import psycopg
import pytest

from tests.local_helpers import private_home, process_alive
from tgsis.db.local import LocalServer, _check_reachable, _OsUser, default_home, find_binaries, throwaway_parent
from tgsis.errors import LocalServerError


@pytest.fixture
def home() -> Iterator[Path]:
    with private_home() as path:
        yield path


def _owner_uid(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Uid:"):
            return int(line.split()[1])
    raise AssertionError("no Uid line")


def test_unknown_binaries_selection_is_refused() -> None:
    with pytest.raises(LocalServerError, match="neither 'auto', 'embedded', 'system' nor a folder"):
        find_binaries("/nonexistent/bin")


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_selected_binaries_are_a_real_server() -> None:
    binaries = find_binaries()
    assert binaries.major >= 15
    assert binaries.describe().startswith(f"PostgreSQL {binaries.version}")
    if os.environ.get("TGSIS_PG") in ("embedded", "system"):
        assert binaries.flavor == os.environ["TGSIS_PG"]


def test_default_home_follows_tgsis_home(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("TGSIS_HOME", str(tmp_path))
    assert default_home() == tmp_path
    monkeypatch.delenv("TGSIS_HOME")
    assert default_home() == (
        Path("/var/lib/tgsis")
        if os.geteuid() == 0
        else Path(os.environ.get("XDG_DATA_HOME") or Path.home() / ".local/share") / "tgsis"
    )


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_throwaway_cluster_settings_and_removal() -> None:
    server = LocalServer.throwaway(in_memory=True)
    try:
        pid = server.pid()
        assert process_alive(pid)
        if os.geteuid() == 0:
            assert _owner_uid(pid) != 0, "the server must not run as root"  # type: ignore[arg-type]
        assert (server.data_dir.stat().st_mode & 0o777) == 0o700
        with psycopg.connect(server.dsn()) as conn:
            settings: dict[str, str] = dict(
                conn.execute(
                    "SELECT name, setting FROM pg_settings WHERE name IN "
                    "('fsync', 'listen_addresses', 'unix_socket_directories', 'full_page_writes', 'max_wal_size')"
                ).fetchall()
            )
            assert settings == {
                "fsync": "off",
                "full_page_writes": "off",
                "listen_addresses": "",
                "unix_socket_directories": str(server.socket_dir),
                "max_wal_size": "256",  # MB: a cluster in memory (throwaway_parent) stays small
            }
            if server.binaries.has_extension_control_path:
                path = conn.execute("SHOW extension_control_path").fetchone()
                assert path == (f"$system:{server.root}",)
        assert server.root.parent == (throwaway_parent() or Path(tempfile.gettempdir()))
    finally:
        server.destroy()
    assert not server.root.exists()
    assert not process_alive(pid)


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
@pytest.mark.one_server  # where the cluster's folder goes: the same on every version
def test_throwaway_clusters_go_to_memory_when_it_has_room(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("TMPDIR", raising=False)
    memory = Path("/dev/shm")
    roomy = memory.is_dir() and os.access(memory, os.W_OK) and shutil.disk_usage(memory).free >= 2 * 1024**3
    assert throwaway_parent() == (memory if roomy else None)
    chosen = Path(tempfile.mkdtemp(prefix="tgsis-tmpdir-"))
    chosen.chmod(0o755)  # the server may run as another OS user (postgres, as root)
    monkeypatch.setenv("TMPDIR", str(chosen))  # a temporary folder chosen by the user wins
    monkeypatch.setattr(tempfile, "tempdir", None)  # (tempfile caches the folder it found first)
    try:
        assert throwaway_parent() is None
        server = LocalServer.throwaway(in_memory=True)
        try:
            assert server.root.parent == chosen
        finally:
            server.destroy()
    finally:
        shutil.rmtree(chosen, ignore_errors=True)


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
@pytest.mark.one_server  # where the cluster's folder goes: the same on every version
def test_a_throwaway_cluster_not_asked_in_memory_stays_in_the_temporary_folder(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the benches' clusters (millions of rows) must neither fill memory nor time a memory disk
    monkeypatch.delenv("TMPDIR", raising=False)
    server = LocalServer.throwaway()
    try:
        assert server.root.parent == Path(tempfile.gettempdir())
    finally:
        server.destroy()


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_persistent_cluster_is_durable_and_listens_on_a_socket(home: Path) -> None:
    server = LocalServer.persistent(home=home)
    assert server.root == home / f"pg{server.binaries.major}"
    with server.acquire():
        with psycopg.connect(server.dsn()) as conn:
            assert conn.execute("SHOW fsync").fetchone() == ("on",)
            assert conn.execute("SHOW listen_addresses").fetchone() == ("",)


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_last_lease_stops_an_implicitly_started_server(home: Path) -> None:
    first = LocalServer.persistent(home=home).acquire()
    server = first.server
    assert server.is_running() and server.started_by() == "implicit"
    second = LocalServer.persistent(home=home).acquire()  # another user of the same cluster
    pid = server.pid()
    first.release()
    assert server.is_running() and server.pid() == pid, "still in use by the second lease"
    second.release()
    assert not server.is_running()
    assert not process_alive(pid)
    first.release()  # releasing twice is harmless


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_explicit_start_outlives_leases(home: Path) -> None:
    server = LocalServer.persistent(home=home)
    assert server.start_explicitly() is True
    assert server.start_explicitly() is False  # already running
    with LocalServer.persistent(home=home).acquire():
        pass
    assert server.is_running() and server.started_by() == "explicit"
    assert server.stop_explicitly() is True
    assert not server.is_running()
    assert server.stop_explicitly() is False


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_stop_waits_for_users_unless_forced(home: Path) -> None:
    lease = LocalServer.persistent(home=home).acquire()
    other = LocalServer.persistent(home=home)
    with pytest.raises(LocalServerError, match="in use by other tgsis processes"):
        other.stop_explicitly(wait=0.3)
    assert other.is_running()
    assert other.stop_explicitly(force=True, wait=0)
    assert not other.is_running()
    lease.release()


@pytest.mark.own_server  # a server of TGSIS_PG's binaries, not the fixture pg's
def test_long_cluster_path_gets_a_short_socket_dir(home: Path) -> None:
    deep = home / ("d" * 60) / ("e" * 60)
    deep.mkdir(parents=True)
    for folder in (deep, deep.parent):
        folder.chmod(0o755)
    server = LocalServer(deep / "pg", find_binaries(), durable=False)
    try:
        server.start()
        assert len(str(server.socket_dir)) < 60 and not str(server.socket_dir).startswith(str(deep))
        with psycopg.connect(server.dsn()) as conn:
            assert conn.execute("SELECT 1").fetchone() == (1,)
    finally:
        server.destroy()
    assert not server.socket_dir.exists()


def test_a_foreign_non_empty_data_dir_is_refused(home: Path) -> None:
    root = home / "pgx"
    (root / "data").mkdir(parents=True)
    (root / "data" / "notes.txt").write_text("mine")
    with pytest.raises(LocalServerError, match="is not empty and holds no PostgreSQL cluster"):
        LocalServer(root, find_binaries()).initdb()
    assert (root / "data" / "notes.txt").read_text() == "mine"


def test_unreachable_cluster_folder_is_explained(home: Path) -> None:
    """As root the server runs as another OS user, who must be able to reach the folder."""
    private = home / "private"
    private.mkdir()
    private.chmod(0o700)
    nobody = _OsUser("nobody", 65534, 65534)
    with pytest.raises(LocalServerError, match="who cannot reach the cluster folder") as info:
        _check_reachable(private / "pg", nobody, "the cluster folder")
    assert f"{private} is not searchable by nobody" in (info.value.detail or "")
    _check_reachable(home / "pg", nobody, "the cluster folder")  # 0755 all the way: fine


def _files(folder: Path) -> dict[str, tuple[int, int]]:
    """Every entry of ``folder``: (size, mtime in ns), symlinks as themselves."""
    return {p.name: (p.lstat().st_size, p.lstat().st_mtime_ns) for p in folder.iterdir()}


def test_a_throwaway_cluster_before_postgresql_18_serves_this_checkouts_extension_without_writing_the_systems() -> None:
    # issue 36: `make test` installed the checkout's files into the system's share folder (PostgreSQL 15 has
    # no extension_control_path); the throwaway cluster now runs on a private copy of the installation
    from tgsis.db.sqlsource import ExtensionSources

    system = find_binaries("system")
    assert system.major < 18, "this machine's system PostgreSQL is 18+: its clusters use extension_control_path"
    assert system.sharedir is not None
    extension_dir = system.sharedir / "extension"
    before = _files(extension_dir)
    sources = ExtensionSources.default()
    server = LocalServer.throwaway(system)
    try:
        assert server.binaries.share is not None and server.binaries.share.is_relative_to(server.root)
        assert server.binaries.sharedir == server.binaries.share
        assert "extension files in" in server.binaries.describe()
        server.ensure_database("ext")
        with psycopg.connect(server.dsn("ext"), autocommit=True) as conn:
            shared = conn.execute("SELECT setting FROM pg_config WHERE name = 'SHAREDIR'").fetchone()
            assert shared is not None and Path(shared[0]).resolve() == server.binaries.share.resolve()
            versions = {
                r[0]
                for r in conn.execute(
                    "SELECT version FROM pg_available_extension_versions WHERE name = 'tgsis'"
                ).fetchall()
            }
            assert sources.version in versions
            # the system's other extensions are still there (PostGIS, contrib)
            system_controls = {p.name.removesuffix(".control") for p in extension_dir.glob("*.control")} - {"tgsis"}
            available = {r[0] for r in conn.execute("SELECT name FROM pg_available_extensions").fetchall()}
            assert system_controls <= available
            conn.execute("CREATE EXTENSION tgsis CASCADE")
            assert conn.execute("SELECT tgsis.version()").fetchone() == (sources.version,)
        written = server.binaries.share / "extension" / f"tgsis--{sources.version}.sql"
        assert written.read_text(encoding="utf-8") == sources.script()
    finally:
        server.destroy()
    assert not server.root.exists()
    assert _files(extension_dir) == before, "the system's extension folder was written"
