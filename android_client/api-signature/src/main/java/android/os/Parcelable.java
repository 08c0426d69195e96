package android.os;

/** Stub: CaptureRequest's interface, so its stub merges with the API 26 signature's class. No members. */
public interface Parcelable {
}
