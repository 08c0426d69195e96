package io.lumipose.client.frame;

/**
 * What the capture result says was actually used for one frame (Camera2 {@code TotalCaptureResult});
 * null where the device did not report it.
 */
public final class CaptureValues {
    public final Long exposureNs;
    public final Integer sensitivityIso;
    public final Long rollingShutterSkewNs;
    public final Long timestampNs;
    /** True for a short-exposure beacon-ID frame (the request's tag says which). */
    public final boolean idFrame;

    public CaptureValues(Long exposureNs, Integer sensitivityIso, Long rollingShutterSkewNs, Long timestampNs) {
        this(exposureNs, sensitivityIso, rollingShutterSkewNs, timestampNs, false);
    }

    public CaptureValues(Long exposureNs, Integer sensitivityIso, Long rollingShutterSkewNs, Long timestampNs,
                         boolean idFrame) {
        this.exposureNs = exposureNs;
        this.sensitivityIso = sensitivityIso;
        this.rollingShutterSkewNs = rollingShutterSkewNs;
        this.timestampNs = timestampNs;
        this.idFrame = idFrame;
    }
}
