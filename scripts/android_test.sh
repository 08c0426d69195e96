#!/usr/bin/env bash
# Android client: build the Maven modules (core on the JVM, app against the Android framework
# classes from Maven Central; both checked against Android API 28's public surface by animal-sniffer)
# and run the core's JUnit 5 tests and the app's Robolectric tests (its Activities and camera code on Android's
# framework classes), including the end-to-end tests against a real `lumipose serve` on
# 127.0.0.1; then the dex check (scripts/android_dex_check.sh). Needs OpenJDK 17 and Maven 3.8; Maven
# downloads everything from Maven Central on first use. Nothing is installed by hand.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$PWD"

# The end-to-end tests start the server from the checkout's venv; the app's resources need Debian's aapt.
[ -x .venv/bin/lumipose ] || bash scripts/setup.sh
bash scripts/system_packages.sh android

MVN=(mvn -B -ntp -f android_client/pom.xml)
# verify also runs the minSdk API check (animal-sniffer against Android API 28, docs/android.md).
"${MVN[@]}" verify -Dlumipose.exe="$ROOT/.venv/bin/lumipose" -Dlumipose.e2e.required=true "$@"

# The -D properties given to this script (e.g. -Dmaven.repo.local) go to the other Maven calls too.
PROPERTIES=()
for arg in "$@"; do
    if [[ "$arg" == -D* ]]; then PROPERTIES+=("$arg"); fi
done

# No invokedynamic in the dex the APK would carry (dx does not desugar; a lambda throws on the phone).
bash scripts/android_dex_check.sh ${PROPERTIES[@]+"${PROPERTIES[@]}"}

# The core also runs on Android, whose org.json differs from Maven Central's (checked JSONException,
# fewer methods): compile the core's main sources against the framework classes alone to prove it.
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT
# The android-all jar is in Maven's local repository, wherever Maven puts it (settings.xml,
# user.home, a -Dmaven.repo.local given to this script): ask Maven (written to a file, since
# its stdout carries colour codes). M2_REPO still overrides.
if [ -n "${M2_REPO:-}" ]; then
    M2="$M2_REPO"
else
    "${MVN[@]}" -N -q org.apache.maven.plugins:maven-help-plugin:3.5.2:evaluate \
        -Dexpression=settings.localRepository -Doutput="$OUT/local-repository" ${PROPERTIES[@]+"${PROPERTIES[@]}"}
    M2="$(cat "$OUT/local-repository")"
fi
AA_VERSION="$(sed -n 's:.*<android.all.version>\(.*\)</android.all.version>.*:\1:p' android_client/pom.xml)"
ANDROID_ALL="$M2/org/robolectric/android-all/$AA_VERSION/android-all-$AA_VERSION.jar"
[ -f "$ANDROID_ALL" ] || { echo "android-all jar not found at $ANDROID_ALL (set M2_REPO)" >&2; exit 1; }
javac --release 8 -nowarn -encoding UTF-8 -cp "$ANDROID_ALL" -d "$OUT/classes" \
    $(find android_client/core/src/main/java -name '*.java')
echo "core compiles against the Android framework's org.json (android-all $AA_VERSION)"
