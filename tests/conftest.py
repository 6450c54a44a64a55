"""Every test that takes `pg`, `db_dsn`, `conn` or `make_database` gets a real
PostgreSQL from the tgsis.testing plugin (see docs/testing.md)."""

pytest_plugins = ["tgsis.testing"]
