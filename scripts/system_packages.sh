#!/usr/bin/env bash
# Debian packages the tests need beyond Python, installed with apt-get when missing (as root, or with sudo):
# Chromium and its driver for the operator page's browser tests (tests/dashboard: Playwright drives
# /usr/bin/chromium; no browser is ever downloaded), redis-server and nginx for the tests of `serve --redis` and
# the replicas (tests/deployment): each test starts its own on a free port; the system services are not used;
# aapt and Android 10's framework-res.apk for the Android app's compiled resources (scripts/android_resources.sh:
# the APK and the app's Robolectric tests).
#   Usage: scripts/system_packages.sh [android]   (android: only what scripts/android_test.sh needs)
set -euo pipefail
missing=()
if [ "${1:-all}" != android ]; then
    [ -x /usr/bin/chromium ] || missing+=(chromium)
    [ -x /usr/bin/chromedriver ] || missing+=(chromium-driver)
    [ -x /usr/bin/redis-server ] || missing+=(redis-server)
    [ -x /usr/sbin/nginx ] || missing+=(nginx)
fi
command -v aapt >/dev/null || missing+=(aapt)
[ -f /usr/share/android-framework-res/framework-res.apk ] || missing+=(android-framework-res)
if [ ${#missing[@]} -gt 0 ]; then
    echo "installing Debian packages for the tests: ${missing[*]}" >&2
    as_root=$([ "$(id -u)" -eq 0 ] || echo sudo)
    $as_root env DEBIAN_FRONTEND=noninteractive apt-get update -qq
    $as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi
