#!/usr/bin/env bash
# Create .venv with Python 3.11 and install Lumipose with its extras (default: the test tools;
# scripts/test.sh also asks for Blender as a module, the simulator's second renderer).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-$(command -v python3.11 || command -v python3)}"
"$PYTHON" -c 'import sys; assert sys.version_info[:2] == (3, 11), f"Python 3.11 needed, found {sys.version}"'
[ -x .venv/bin/python ] || "$PYTHON" -m venv .venv
.venv/bin/python -m pip install --quiet --upgrade pip
EXTRAS="${1:-test}"
.venv/bin/python -m pip install --quiet -e ".[$EXTRAS]"
# numba compiles the pipeline's kernels once into __pycache__: here, not in a user's first `lumipose locate`
echo "setup: compiling the pipeline's kernels (numba, once: about 15 s; cached afterwards)"
.venv/bin/python -c "from server.pipeline import warm_kernels; warm_kernels()"
