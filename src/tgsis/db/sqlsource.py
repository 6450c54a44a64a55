"""The extension's SQL sources, as the Python client sees them.

``sql/Makefile`` (PGXS) and this module build the same script from the same
files: ``sources.txt`` gives the order, ``tgsis.control`` the version, and
``@TGSIS_VERSION@`` in the sources is replaced by it. Upgrade scripts are
``updates/tgsis--FROM--TO.sql`` (frozen) or assembled from
``upgrade/tgsis--FROM--TO.sql`` (:mod:`tgsis.db._upgrade`), installed by PGXS
and applied by :func:`tgsis.install` on the plain-SQL route.

The sources are found, in this order, in ``$TGSIS_SQL_DIR``, inside the
installed package (``tgsis/_sql``, put there by the wheel build) or in the
``sql/`` folder of a source checkout.
"""

from __future__ import annotations

import collections
import os
import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from tgsis.db._upgrade import FINGERPRINT_TOKEN, Upgrade, assemble, fingerprint, header_for, install_text
from tgsis.errors import InstallationError

__all__ = ["ExtensionSources", "find_sql_dir", "parse_version", "EXTENSION"]

EXTENSION = "tgsis"
VERSION_TOKEN = "@TGSIS_VERSION@"
PSQL_GUARD = '\\echo Use "CREATE EXTENSION tgsis" to load this file. \\quit'

_CONTROL_VERSION_RE = re.compile(r"^default_version\s*=\s*'([^']+)'", re.MULTILINE)
_CONTROL_REQUIRES_RE = re.compile(r"^requires\s*=\s*'([^']*)'", re.MULTILINE)
_UPDATE_RE = re.compile(rf"^{EXTENSION}--([0-9][0-9.]*)--([0-9][0-9.]*)\.sql$")
_VERSION_RE = re.compile(r"^[0-9]+(\.[0-9]+)*$")
_GUARD_RE = re.compile(r'^\\echo Use "[^"]*" to load this file\. \\quit\s*$')


def parse_version(version: str) -> tuple[int, ...]:
    """Return a dotted version ``"1.2.3"`` as a comparable tuple ``(1, 2, 3)``.

    Raises
    ------
    InstallationError
        If ``version`` is not dotted decimal numbers.
    """
    if not _VERSION_RE.match(version):
        raise InstallationError(f"tgsis version {version!r} is not of the form N.N.N")
    return tuple(int(part) for part in version.split("."))


def find_sql_dir() -> Path:
    """Return the folder holding ``tgsis.control`` and the SQL sources.

    Raises
    ------
    InstallationError
        If no folder with a ``tgsis.control`` is found.
    """
    here = Path(__file__).resolve()
    candidates: list[Path] = []
    if env := os.environ.get("TGSIS_SQL_DIR"):
        candidates.append(Path(env))
    candidates.append(here.parents[1] / "_sql")  # installed wheel
    candidates.append(here.parents[3] / "sql")  # source checkout: src/tgsis/db/ -> repo
    for candidate in candidates:
        if (candidate / f"{EXTENSION}.control").is_file():
            return candidate
    raise InstallationError(
        "cannot find the tgsis SQL sources",
        detail="looked in: " + ", ".join(str(c) for c in candidates),
        hint="set TGSIS_SQL_DIR to the sql/ folder of a tgsis checkout",
    )


@dataclass(frozen=True)
class ExtensionSources:
    """The SQL sources of one tgsis version.

    Parameters
    ----------
    root : Path
        Folder with ``tgsis.control``, ``sources.txt``, the listed files and
        ``updates/``.
    """

    root: Path

    @classmethod
    def default(cls) -> ExtensionSources:
        """Sources found by :func:`find_sql_dir`."""
        return cls(find_sql_dir())

    @cached_property
    def control(self) -> str:
        """Text of ``tgsis.control``."""
        return (self.root / f"{EXTENSION}.control").read_text(encoding="utf-8")

    @cached_property
    def version(self) -> str:
        """``default_version`` of the control file."""
        match = _CONTROL_VERSION_RE.search(self.control)
        if match is None:
            raise InstallationError(f"{self.root / 'tgsis.control'} has no default_version")
        parse_version(match.group(1))
        return match.group(1)

    @cached_property
    def requires(self) -> list[str]:
        """Extensions tgsis needs (``requires`` of the control file), e.g. ``["cube"]``."""
        match = _CONTROL_REQUIRES_RE.search(self.control)
        return [name.strip() for name in match.group(1).split(",") if name.strip()] if match else []

    @cached_property
    def files(self) -> list[str]:
        """Source files in install order, relative to :attr:`root`."""
        listing = (self.root / "sources.txt").read_text(encoding="utf-8")
        names = [line.split("#", 1)[0].strip() for line in listing.splitlines()]
        return [name for name in names if name]

    def script(self, *, psql_guard: bool = True) -> str:
        """The install script ``tgsis--<version>.sql``.

        Parameters
        ----------
        psql_guard : bool
            Keep the ``\\echo ... \\quit`` line that stops psql from running
            the file by hand. ``False`` gives the SQL a driver can execute.
        """
        script = self._unfingerprinted.replace(FINGERPRINT_TOKEN, self.fingerprint)
        return script if psql_guard else script.replace(PSQL_GUARD + "\n", "", 1)

    @cached_property
    def _unfingerprinted(self) -> str:
        return install_text(self.version, self.source_texts())

    @cached_property
    def fingerprint(self) -> str:
        """The fingerprint of this version's install script as built (``tgsis.installation.fingerprint``).

        Two builds of one version from different sources (a development version at two commits) have
        different fingerprints: :func:`tgsis.install` and ``tgsis db status`` compare it.
        """
        return fingerprint(self._unfingerprinted)

    @cached_property
    def updates(self) -> dict[tuple[str, str], Path]:
        """Upgrade scripts by ``(from_version, to_version)``.

        ``updates/tgsis--A--B.sql`` are complete scripts (frozen when B was
        released); ``upgrade/tgsis--A--B.sql`` with B this version are the
        hand-written parts of the scripts :meth:`update_script` assembles
        (:mod:`tgsis.db._upgrade`).
        """
        found: dict[tuple[str, str], Path] = {}
        for folder in (self.root / "updates", self.root / "upgrade"):
            if folder.is_dir():
                for path in sorted(folder.iterdir()):
                    match = _UPDATE_RE.match(path.name)
                    if match and (folder.name == "updates" or match.group(2) == self.version):
                        found[(match.group(1), match.group(2))] = path
        return found

    @cached_property
    def frozen_scripts(self) -> dict[str, Path]:
        """Install scripts of released versions, ``upgrade/tgsis--A.sql``, by version (the upgrade tests install them)."""
        folder = self.root / "upgrade"
        if not folder.is_dir():
            return {}
        return {
            m.group(1): path
            for path in sorted(folder.iterdir())
            if (m := re.match(rf"^{EXTENSION}--([0-9][0-9.]*)\.sql$", path.name)) and m.group(1) != self.version
        }

    def source_texts(self) -> dict[str, str]:
        """``{file: text}`` of the sources in install order, ``@TGSIS_VERSION@`` replaced."""
        return {
            name: (self.root / name).read_text(encoding="utf-8").replace(VERSION_TOKEN, self.version)
            for name in self.files
        }

    def upgrade(self, from_version: str) -> Upgrade:
        """The assembled upgrade from ``from_version`` to this version (its parts, :attr:`~tgsis.db._upgrade.Upgrade.unhandled`)."""
        return assemble(self.root, from_version, self.version, self.source_texts())

    def update_script(self, path: Path) -> str:
        """The text of an upgrade script of :attr:`updates` as PostgreSQL's extension folder holds it."""
        match = _UPDATE_RE.match(path.name)
        if path.parent.name == "upgrade" and match:
            return self.upgrade(match.group(1)).script(header_for(match.group(1), match.group(2)))
        return path.read_text(encoding="utf-8")

    def upgrade_path(self, from_version: str, to_version: str) -> list[Path]:
        """Shortest chain of upgrade scripts from one version to another.

        Raises
        ------
        InstallationError
            If no chain of ``updates/`` scripts connects the two versions.
        """
        if from_version == to_version:
            return []
        previous: dict[str, tuple[str, Path]] = {}
        queue = collections.deque([from_version])
        seen = {from_version}
        while queue:
            current = queue.popleft()
            for (start, end), path in self.updates.items():
                if start == current and end not in seen:
                    seen.add(end)
                    previous[end] = (current, path)
                    queue.append(end)
        if to_version not in previous:
            raise InstallationError(
                f"no upgrade path from tgsis {from_version} to {to_version}",
                detail=f"upgrade scripts in {self.root / 'updates'}: "
                + (", ".join(p.name for p in self.updates.values()) or "none"),
            )
        chain: list[Path] = []
        version = to_version
        while version != from_version:
            version, path = previous[version]
            chain.append(path)
        return chain[::-1]

    def upgrade_sql(self, path: Path) -> str:
        """An upgrade script as a driver can execute it (psql guard removed)."""
        lines = self.update_script(path).splitlines(keepends=True)
        return "".join(line for line in lines if not _GUARD_RE.match(line))

    def write_extension_dir(self, prefix: Path) -> Path:
        """Write control file and scripts as PostgreSQL expects them in ``prefix/extension``.

        PostgreSQL 18's ``extension_control_path`` appends ``/extension`` to
        each of its entries, so ``prefix`` is what goes into that setting.

        Returns
        -------
        Path
            ``prefix / "extension"``.
        """
        target = prefix / "extension"
        target.mkdir(parents=True, exist_ok=True)
        files = {f"{EXTENSION}.control": self.control, f"{EXTENSION}--{self.version}.sql": self.script()}
        for path in self.updates.values():
            files[path.name] = self.update_script(path)
        for path in self.frozen_scripts.values():
            files[path.name] = path.read_text(encoding="utf-8")
        for name, text in files.items():
            destination = target / name
            if not destination.exists() or destination.read_text(encoding="utf-8") != text:
                tmp = destination.with_suffix(destination.suffix + ".tmp")
                tmp.write_text(text, encoding="utf-8")
                tmp.replace(destination)
        return target
