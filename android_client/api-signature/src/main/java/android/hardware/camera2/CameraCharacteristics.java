package android.hardware.camera2;

/**
 * API 28 additions the app reads, merged into the public API 26 signature (api-signature/pom.xml). Each is
 * "Added in API level 28" in the CameraCharacteristics reference.
 */
public final class CameraCharacteristics extends CameraMetadata<CameraCharacteristics.Key<?>> {
    public static final Key<float[]> LENS_DISTORTION = null;
    public static final Key<int[]> DISTORTION_CORRECTION_AVAILABLE_MODES = null;

    private CameraCharacteristics() {
    }

    public static final class Key<T> {
        private Key() {
        }
    }
}
