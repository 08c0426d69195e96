#!/usr/bin/env bash
# Set up (idempotent) and locate the bundled fixture, then start the service once it exists.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/lumipose "$@"
