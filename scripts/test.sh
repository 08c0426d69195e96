#!/usr/bin/env bash
# Set up (idempotent; with Blender as a module and the Debian packages the tests need), check the code (ruff lint and format, mypy), then run the whole test suite.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/system_packages.sh  # Chromium, redis-server, nginx: apt-get when missing
bash scripts/setup.sh test,blender  # Blender's tests run, not skip (issue 13; ~860 MB installed)
.venv/bin/ruff check
.venv/bin/ruff format --check
.venv/bin/mypy
.venv/bin/python -m pytest "$@"
