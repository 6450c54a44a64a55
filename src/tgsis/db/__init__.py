"""Database side of the client: connections, installation, the local server."""

from tgsis.db.connect import Target, connect, local_dsn, release_local_server, resolve_target
from tgsis.db.install import (
    InstallationStatus,
    InstalledVersion,
    InstallResult,
    install,
    installation_status,
    installed_version,
    partition_model_storage,
    uninstall,
)
from tgsis.db.local import Lease, LocalServer, PgBinaries, default_home, find_binaries
from tgsis.db.sqlsource import ExtensionSources

__all__ = [
    "ExtensionSources",
    "InstallResult",
    "InstallationStatus",
    "InstalledVersion",
    "Lease",
    "LocalServer",
    "PgBinaries",
    "Target",
    "connect",
    "default_home",
    "find_binaries",
    "install",
    "installation_status",
    "installed_version",
    "partition_model_storage",
    "local_dsn",
    "release_local_server",
    "resolve_target",
    "uninstall",
]
