#!/usr/bin/env bash
# The Android client's JVM benchmark (issue 12): full-size Mi 8 front frames 1, 2 and 3 m below a
# panel (pose frames and their ID bursts), rendered once by `lumipose simulate` into
# android_client/target/android-bench/, played by the replay camera through the app's path
# (FramePipeline, beacon windows, burst uploads) to a real `lumipose serve` started from the
# checkout's venv. Prints one JSON object with --json, else a table (progress on stderr).
# Offline after Maven's first download.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$PWD"
[ -x .venv/bin/lumipose ] || bash scripts/setup.sh

MVN=(mvn -B -ntp -q -f android_client/pom.xml)
CLASSPATH_FILE="$ROOT/android_client/core/target/bench.classpath"
echo "building the core and its tests" >&2
"${MVN[@]}" -pl core test-compile dependency:build-classpath -Dmdep.includeScope=test \
    -Dmdep.outputFile="$CLASSPATH_FILE" >&2
CORE="$ROOT/android_client/core/target"
exec java -Xmx1500m -cp "$CORE/test-classes:$CORE/classes:$(cat "$CLASSPATH_FILE")" \
    -Dlumipose.repo="$ROOT" -Dlumipose.exe="$ROOT/.venv/bin/lumipose" \
    io.lumipose.client.e2e.AndroidBench --cache "$ROOT/android_client/target/android-bench" "$@"
