# Developer entry points. The README's quickstart uses `make demo` and `make test`;
# .ci/run is `make test` and nothing else (tests/test_make_test.py checks).

PYTHON ?= python3
VENV   ?= .venv
BIN     = $(VENV)/bin
PYTEST_ARGS ?=

.PHONY: all install demo test setup check typecheck lint format extension installcheck clean pictures

# A bare `make` builds the extension scripts and `make install` installs them
# (PGXS, the PostgreSQL of pg_config): what `pgxn install tgsis` runs (META.json).
all:
	$(MAKE) --no-print-directory -C sql

install:
	$(MAKE) --no-print-directory -C sql install

# A venv with tgsis (editable), its test tools and the embedded PostgreSQL 18.
# (Debian ships venv's ensurepip apart: python3-venv, installed when missing, saying so)
$(VENV)/.installed: pyproject.toml
	@$(PYTHON) -c 'import ensurepip' 2>/dev/null || tools/setup-machine python3-venv
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet --editable '.[test,embedded,view]'
	touch $@

# (run as root, the local server runs as the OS user postgres, TGSIS_PG_OS_USER or not at all:
# on a fresh Debian that user comes with the package postgresql-common, installed when missing, saying so)
demo: $(VENV)/.installed
	@if [ "$$(id -u)" -eq 0 ] && [ -z "$${TGSIS_PG_OS_USER:-}" ] && ! id postgres >/dev/null 2>&1; then \
	    tools/setup-machine postgresql-common; fi
	$(BIN)/tgsis demo

# The whole test suite, as CI runs it, on a fresh Debian/Ubuntu machine: the
# system packages it needs, installed when missing (tools/setup-machine says
# which before it does), the venv, the type check and lint, then the suite on
# the system's PostgreSQL 15 and on the embedded 18 (in a copy of the
# repository with nothing beside it) side by side (tools/test-suites);
# TGSIS_PG=embedded|system (or TGSIS_TEST_DSN): that server only.
# Nothing is written outside the checkout and temporary folders but the system
# packages: the throwaway clusters of PostgreSQL 15 read this checkout's
# extension files from a private copy of its share folder (docs/testing.md).
test:
	@tools/setup-machine
	@$(MAKE) --no-print-directory $(VENV)/.installed check
	VENV=$(VENV) tools/test-suites $(PYTEST_ARGS)

# The system packages `make test` needs, installed when missing (as root or with sudo).
setup:
	@tools/setup-machine

# The pictures the README shows, made by the scenarios (tgsis demo NAME) on the local server.
pictures: $(VENV)/.installed
	rm -rf build/pictures && mkdir -p build/pictures docs/pictures
	$(BIN)/tgsis demo saltdome --dir build/pictures
	$(BIN)/tgsis demo synsed --dir build/pictures
	$(BIN)/tgsis demo river --dir build/pictures
	$(BIN)/tgsis demo interpretations --dir build/pictures
	$(BIN)/tgsis demo mine --dir build/pictures
	$(BIN)/tgsis demo knowledge --dir build/pictures
	$(BIN)/tgsis demo merge --dir build/pictures
	$(BIN)/tgsis demo --dir build/pictures
	$(BIN)/python docs/view_pictures.py --dir build/pictures   # tgsis view of the demo in headless Chromium
	cp build/pictures/saltdome_t2_3.png build/pictures/saltdome.gif build/pictures/synsed_t2_5.png \
	    build/pictures/river_t4.png build/pictures/interpretations_model3.png build/pictures/mine_ore_top.png \
	    build/pictures/knowledge_interpretations.png build/pictures/view_scene.png build/pictures/view_time.png \
	    build/pictures/view_compare.png build/pictures/merge_resolved.png docs/pictures/
	cp build/pictures/cfm_release_6.1_over_5.3.png docs/pictures/

# what ruff format keeps formatted: the whole tree of Python code (docs/developing.md, "Lint and format")
RUFF_FORMATTED = src tests bench

check: typecheck lint
	$(BIN)/ruff format --check $(RUFF_FORMATTED)

# The hooks of pre-commit (.pre-commit-config.yaml) run these, with the venv's tools: the checks of
# `make check`, one tool each; `format` writes what `check` checks.
typecheck: $(VENV)/.installed
	$(BIN)/python -m mypy

lint: $(VENV)/.installed
	$(BIN)/ruff check $(RUFF_FORMATTED)

format: $(VENV)/.installed
	$(BIN)/ruff format $(RUFF_FORMATTED)

# Build the extension script; install it into the system PostgreSQL (PGXS) when
# this user may write there, so that CREATE EXTENSION tgsis works on it too
# (`make test` does not need it: its clusters read this checkout's files).
extension:
	@if command -v pg_config >/dev/null 2>&1; then \
	    $(MAKE) --no-print-directory -C sql; \
	    if [ -w "$$(pg_config --sharedir)/extension" ]; then \
	        $(MAKE) --no-print-directory -C sql install; \
	    else \
	        echo "note: cannot write $$(pg_config --sharedir)/extension: run 'sudo make -C sql install' for CREATE EXTENSION on the system PostgreSQL"; \
	    fi; \
	else \
	    echo "note: no pg_config on PATH: the extension is not built for a system PostgreSQL"; \
	fi

# The pg_regress tests of sql/test against the installed extension on a running
# server (PGHOST, PGPORT, PGUSER: a superuser), as a DBA or packager checks an
# install: make extension (or sudo make -C sql install) first.
installcheck:
	$(MAKE) --no-print-directory -C sql installcheck

clean:
	$(MAKE) -C sql clean
	rm -rf $(VENV) .pytest_cache .mypy_cache
