#!/usr/bin/env bash
# Set up (idempotent), then run `lumipose` with the given arguments (the HTTP service is the next issue).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/lumipose "$@"
