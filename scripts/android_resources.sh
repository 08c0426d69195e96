#!/usr/bin/env bash
# The app's compiled resources, as Gradle's merge step would make them, from Debian's aapt and Android 10's
# framework-res.apk: OUT/AndroidManifest.xml (the source manifest with its package, which the Gradle-style
# source leaves to the build) and OUT/resources.apk (manifest + res/, compiled). Used by
# scripts/android_apk.sh (the APK) and by the app's Robolectric tests (app/pom.xml runs it before them).
#   Usage: scripts/android_resources.sh OUT
#   Debian packages needed: aapt android-framework-res
set -euo pipefail
OUT="${1:?usage: android_resources.sh OUT}"
APP="$(cd "$(dirname "$0")/../android_client/app" && pwd)"
FRAMEWORK_RES=/usr/share/android-framework-res/framework-res.apk
missing=()
command -v aapt >/dev/null || missing+=(aapt)
[ -f "$FRAMEWORK_RES" ] || missing+=(android-framework-res)
if [ ${#missing[@]} -gt 0 ]; then
    echo "missing Debian packages: ${missing[*]}; install them with: apt-get install ${missing[*]}" >&2
    exit 1
fi
mkdir -p "$OUT"
sed 's|<manifest xmlns:android="http://schemas.android.com/apk/res/android">|<manifest xmlns:android="http://schemas.android.com/apk/res/android" package="io.lumipose.app">|' \
    "$APP/src/main/AndroidManifest.xml" > "$OUT/AndroidManifest.xml"
grep -q 'package="io.lumipose.app"' "$OUT/AndroidManifest.xml"
aapt package -f -M "$OUT/AndroidManifest.xml" -S "$APP/src/main/res" -I "$FRAMEWORK_RES" \
    --min-sdk-version 28 --target-sdk-version 29 --version-code 1 --version-name 0.1.0 -F "$OUT/resources.apk"
