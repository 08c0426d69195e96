#!/usr/bin/env bash
# Debian packages the tests need beyond Python, installed with apt-get when missing (as root, or with sudo):
# Chromium and its driver for the operator page's browser tests (tests/dashboard: Playwright drives
# /usr/bin/chromium; no browser is ever downloaded), redis-server and nginx for the tests of `serve --redis` and
# the replicas (tests/deployment): each test starts its own on a free port; the system services are not used.
set -euo pipefail
missing=()
[ -x /usr/bin/chromium ] || missing+=(chromium)
[ -x /usr/bin/chromedriver ] || missing+=(chromium-driver)
[ -x /usr/bin/redis-server ] || missing+=(redis-server)
[ -x /usr/sbin/nginx ] || missing+=(nginx)
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing Debian packages for the tests: ${missing[*]}" >&2
    as_root=$([ "$(id -u)" -eq 0 ] || echo sudo)
    $as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    $as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
