#!/usr/bin/env bash
# Optional: build a signed debug APK of the Android client offline, from Maven Central and Debian's
# packages only (no Android SDK, no Gradle): Maven compiles the modules, dx (dalvik-dx from Maven
# Central, scripts/android_dex.sh) dexes them, Debian's aapt packages the manifest against Android 10's
# framework-res.apk, zipalign aligns, apksigner signs with a throw-away debug key, and both tools check the result.
#   Debian packages needed: aapt zipalign apksigner android-framework-res
#   Output: android_client/app/target/apk/lumipose-debug.apk
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT="$PWD"
FRAMEWORK_RES=/usr/share/android-framework-res/framework-res.apk

missing=()
for tool in aapt zipalign apksigner; do
    command -v "$tool" >/dev/null || missing+=("$tool")
done
[ -f "$FRAMEWORK_RES" ] || missing+=(android-framework-res)
if [ ${#missing[@]} -gt 0 ]; then
    echo "missing Debian packages: ${missing[*]}; install them with: apt-get install ${missing[*]}" >&2
    exit 1
fi

OUT=android_client/app/target/apk
mkdir -p "$OUT"
MVN=(mvn -B -ntp -q -f android_client/pom.xml)
"${MVN[@]}" package -DskipTests
rm -f "$OUT"/*.apk "$OUT"/classes.dex

# Resources: the manifest and strings only (the screens are built in code, so no R class is needed), compiled
# as the Robolectric tests read them.
bash scripts/android_resources.sh "$OUT"
mv "$OUT/resources.apk" "$OUT/unsigned.apk"

# Dex the app and the core (dx, minSdk 28; the same step as the dex check's); org.json and android.* come from
# the phone's framework.
bash scripts/android_dex.sh "$OUT/classes.dex"
(cd "$OUT" && aapt add unsigned.apk classes.dex >/dev/null)
# The core's Java resource (the capture protocol, as core/pom.xml bundles it) at the APK's root, where
# Android's class loader serves it to CaptureProtocol.
PROTOCOL=io/lumipose/client/protocol/capture_protocol.json
rm -rf "$OUT/resources" && mkdir -p "$OUT/resources/$(dirname "$PROTOCOL")"
cp shared_schemas/capture_protocol.json "$OUT/resources/$PROTOCOL"
(cd "$OUT/resources" && aapt add "$ROOT/$OUT/unsigned.apk" "$PROTOCOL" >/dev/null)

zipalign -f 4 "$OUT/unsigned.apk" "$OUT/aligned.apk"
KEYSTORE="$OUT/debug.keystore"
[ -f "$KEYSTORE" ] || keytool -genkeypair -noprompt -keystore "$KEYSTORE" -storepass android -keypass android \
    -alias lumipose-debug -keyalg RSA -keysize 2048 -validity 10000 -dname "CN=Lumipose debug" >/dev/null 2>&1
apksigner sign --ks "$KEYSTORE" --ks-pass pass:android --key-pass pass:android \
    --out "$OUT/lumipose-debug.apk" "$OUT/aligned.apk"
rm -f "$OUT/unsigned.apk" "$OUT/aligned.apk"

apksigner verify --verbose "$OUT/lumipose-debug.apk"
aapt list "$OUT/lumipose-debug.apk" | grep -qx "$PROTOCOL" || { echo "the APK lacks $PROTOCOL" >&2; exit 1; }
aapt dump badging "$OUT/lumipose-debug.apk" | grep -E "^(package|sdkVersion|targetSdkVersion|uses-permission|launchable-activity)"
echo "APK: $OUT/lumipose-debug.apk ($(stat -c %s "$OUT/lumipose-debug.apk") bytes)"
