#!/usr/bin/env bash
# Dex the Android client's core and app jars as the APK carries them: dx (dalvik-dx from Maven Central; it does
# not desugar, so the code must have no lambdas), --min-sdk-version=28 (the app's minSdk). org.json and android.*
# come from the phone's framework. The one dx step for scripts/android_apk.sh and scripts/android_dex_check.sh.
#   Needs the jars built first (mvn package); extra arguments go to Maven (e.g. -Dmaven.repo.local=...).
#   Usage: scripts/android_dex.sh OUTPUT.dex [MAVEN_ARGS...]
set -euo pipefail
cd "$(dirname "$0")/.."
OUTPUT="$1"
shift
DX_VERSION=11.0.0_r3
TOOLS=android_client/app/target/tools
DX="$TOOLS/dalvik-dx-$DX_VERSION.jar"
[ -f "$DX" ] || mvn -B -ntp -q -Dstyle.color=never -f android_client/pom.xml -N org.apache.maven.plugins:maven-dependency-plugin:3.8.1:copy \
    -Dartifact=com.jakewharton.android.repackaged:dalvik-dx:$DX_VERSION -DoutputDirectory="$PWD/$TOOLS" "$@"
mkdir -p "$(dirname "$OUTPUT")"
rm -f "$OUTPUT"
# The main jars only: the core's test-jar (for the app's Robolectric tests) sits beside them.
JARS=()
for jar in android_client/core/target/lumipose-client-core-*.jar android_client/app/target/lumipose-android-app-*.jar; do
    [[ "$jar" == *-tests.jar ]] || JARS+=("$jar")
done
java -cp "$DX" com.android.dx.command.Main --dex --min-sdk-version=28 --output="$OUTPUT" "${JARS[@]}"
