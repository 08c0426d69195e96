#!/usr/bin/env bash
# Dex check (docs/android.md, "Dex and API level checks"): dex the core and app jars exactly as the APK does
# (scripts/android_dex.sh) and fail on any invokedynamic that reached the dex, naming its class and method:
# invoke-custom (lambdas, method references, Java 9+ string concatenation), invoke-polymorphic (MethodHandle
# calls), const-method-handle / const-method-type. dx does not desugar and Android has no usable
# LambdaMetafactory, so on a phone such a call throws the first time it runs. The dex is read by dexlib2 (the
# smali project's library, from Maven Central; pure Java, cached in Maven's local repository like dx).
#   Needs the jars built first (mvn package); extra arguments go to Maven (e.g. -Dmaven.repo.local=...).
set -euo pipefail
cd "$(dirname "$0")/.."
OUT=android_client/app/target/dex-check
TOOLS=android_client/app/target/tools
bash scripts/android_dex.sh "$OUT/classes.dex" "$@"
CP=()
for artifact in org.smali:dexlib2:2.5.2 com.google.guava:guava:27.1-android; do
    IFS=: read -r _ name version <<< "$artifact"
    jar="$TOOLS/$name-$version.jar"
    [ -f "$jar" ] || mvn -B -ntp -q -Dstyle.color=never -f android_client/pom.xml -N org.apache.maven.plugins:maven-dependency-plugin:3.8.1:copy \
        -Dartifact="$artifact" -DoutputDirectory="$PWD/$TOOLS" "$@"
    CP+=("$jar")
done
java -cp "$(IFS=:; echo "${CP[*]}")" scripts/DexCheck.java "$OUT/classes.dex"
