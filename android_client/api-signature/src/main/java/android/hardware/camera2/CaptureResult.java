package android.hardware.camera2;

/** API 28 additions the app reads (api-signature/pom.xml); "Added in API level 28" in the CaptureResult reference. */
public class CaptureResult extends CameraMetadata<CaptureResult.Key<?>> {
    public static final Key<float[]> LENS_DISTORTION = null;
    public static final Key<Integer> DISTORTION_CORRECTION_MODE = null;

    private CaptureResult() {
    }

    public static final class Key<T> {
        private Key() {
        }
    }
}
