#!/usr/bin/env bash
# Set up (idempotent), then run the HTTP service: `bash scripts/serve.sh [serve flags]`.
# Defaults: http://127.0.0.1:8000, the bundled demo map and device profiles, data in ./data.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
exec .venv/bin/lumipose serve "$@"
