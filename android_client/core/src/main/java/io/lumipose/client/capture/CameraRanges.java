package io.lumipose.client.capture;

/**
 * What one camera advertises for manual capture, copied out of Camera2's
 * {@code CameraCharacteristics} as plain numbers (null = not advertised).
 *
 * <p>{@code streamMinFrameDurationNs} is the YUV_420_888 stream's minimum frame duration at the
 * chosen output size ({@code StreamConfigurationMap.getOutputMinFrameDuration}), 0 when unknown.
 */
public final class CameraRanges {
    public final boolean manualSensor;
    public final Long exposureMinNs;
    public final Long exposureMaxNs;
    public final Integer sensitivityMinIso;
    public final Integer sensitivityMaxIso;
    public final Long maxFrameDurationNs;
    public final long streamMinFrameDurationNs;

    public CameraRanges(boolean manualSensor, Long exposureMinNs, Long exposureMaxNs,
                        Integer sensitivityMinIso, Integer sensitivityMaxIso,
                        Long maxFrameDurationNs, long streamMinFrameDurationNs) {
        if ((exposureMinNs == null) != (exposureMaxNs == null)) {
            throw new IllegalArgumentException("exposure range: give both ends or neither");
        }
        if (exposureMinNs != null && (exposureMinNs <= 0 || exposureMinNs > exposureMaxNs)) {
            throw new IllegalArgumentException("exposure range [" + exposureMinNs + ", " + exposureMaxNs
                    + "] ns is not a positive interval");
        }
        if ((sensitivityMinIso == null) != (sensitivityMaxIso == null)) {
            throw new IllegalArgumentException("sensitivity range: give both ends or neither");
        }
        if (sensitivityMinIso != null && (sensitivityMinIso <= 0 || sensitivityMinIso > sensitivityMaxIso)) {
            throw new IllegalArgumentException("sensitivity range [" + sensitivityMinIso + ", " + sensitivityMaxIso
                    + "] ISO is not a positive interval");
        }
        if (maxFrameDurationNs != null && maxFrameDurationNs <= 0) {
            throw new IllegalArgumentException("maxFrameDurationNs must be > 0, got " + maxFrameDurationNs);
        }
        if (streamMinFrameDurationNs < 0) {
            throw new IllegalArgumentException("streamMinFrameDurationNs must be >= 0, got " + streamMinFrameDurationNs);
        }
        this.manualSensor = manualSensor;
        this.exposureMinNs = exposureMinNs;
        this.exposureMaxNs = exposureMaxNs;
        this.sensitivityMinIso = sensitivityMinIso;
        this.sensitivityMaxIso = sensitivityMaxIso;
        this.maxFrameDurationNs = maxFrameDurationNs;
        this.streamMinFrameDurationNs = streamMinFrameDurationNs;
    }
}
