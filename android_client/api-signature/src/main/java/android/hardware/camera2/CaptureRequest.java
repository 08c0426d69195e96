package android.hardware.camera2;

/** API 28 additions the app sets (api-signature/pom.xml); "Added in API level 28" in the CaptureRequest reference. */
public final class CaptureRequest extends CameraMetadata<CaptureRequest.Key<?>> implements android.os.Parcelable {
    public static final Key<Integer> DISTORTION_CORRECTION_MODE = null;

    private CaptureRequest() {
    }

    public static final class Key<T> {
        private Key() {
        }
    }
}
