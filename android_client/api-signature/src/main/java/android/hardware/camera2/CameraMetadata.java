package android.hardware.camera2;

/** Stub for the API 28 signature (api-signature/pom.xml): same superclass as the framework's, no members of its own. */
public abstract class CameraMetadata<TKey> {
    CameraMetadata() {
    }
}
