#!/usr/bin/env bash
# What can be checked of docker/Dockerfile without a Docker engine: its build-stage COPY
# sources go into a clean folder, its install steps run into a clean venv, and the installed
# service starts with the image's environment and answers the image's HEALTHCHECK and a locate.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON="${PYTHON:-$(command -v python3.11 || command -v python3)}"
work="$(mktemp -d)"
# the service stopped and waited for before its folder goes: its start-up thread may still be writing numba's cache
trap 'kill "${server:-0}" 2>/dev/null || true; wait "${server:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT

mkdir -p "$work/src" "$work/data"
# COPY lines of the build stage: "COPY a b ./" or "COPY dir ./dir"
grep -E '^COPY [^-]' docker/Dockerfile | while read -r _ args; do
  set -- $args
  for source in "${@:1:$#-1}"; do cp -r "$source" "$work/src/"; done
done
"$PYTHON" -m venv "$work/venv"
"$work/venv/bin/pip" install --quiet --upgrade pip
"$work/venv/bin/pip" install --quiet "$work/src[redis]"  # the image installs the redis extra

port=$("$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
# the image's environment: its NUMBA_CACHE_DIR too (the installed package is not the service user's to write)
(cd "$work/data" && LUMIPOSE_HOST=127.0.0.1 LUMIPOSE_PORT=$port LUMIPOSE_DATA_DIR="$work/data" \
  NUMBA_CACHE_DIR="$work/numba-cache" exec "$work/venv/bin/lumipose" serve --log-level warning) &
server=$!
healthcheck=$(grep -oE "urllib.request.urlopen\('[^']+'" docker/Dockerfile | sed "s/8000/$port/; s/urllib.request.urlopen(//")
for _ in $(seq 60); do
  if "$work/venv/bin/python" -c "import urllib.request; urllib.request.urlopen($healthcheck, timeout=2)" 2>/dev/null; then
    break
  fi
  sleep 0.5
done
"$work/venv/bin/python" -c "import urllib.request; urllib.request.urlopen($healthcheck, timeout=2)"
"$work/venv/bin/lumipose" client --url "http://127.0.0.1:$port" locate tests/fixtures/bench_1m.json --json > "$work/result.json"
grep -q '"ok": true' "$work/result.json"
# the operator's page ships in the package: every file of the repository's page is installed and served
"$work/venv/bin/python" -I - "http://127.0.0.1:$port" server/dashboard/static <<'PY'
import sys, urllib.request
from pathlib import Path
from server.dashboard import STATIC_DIR  # the installed package's (-I: not the repository's)
base, source = sys.argv[1], Path(sys.argv[2])
files = sorted(p.name for p in source.iterdir())
missing = sorted(set(files) - {p.name for p in STATIC_DIR.iterdir()})
assert not missing, f"the package leaves out the page's {missing}"
assert "<html" in urllib.request.urlopen(f"{base}/dashboard/", timeout=5).read().decode()
for name in files:
    urllib.request.urlopen(f"{base}/dashboard/static/{name}", timeout=5).read()
print(f"docker_check: the operator's page and its {len(files)} files are installed and served")
PY
echo "docker_check: the image's install steps give a service that passes its healthcheck and locates the fixture"
