package io.lumipose.client.capture;

import io.lumipose.client.protocol.CaptureProtocol;

/** What the user and the map ask of the capture; the camera's facts then decide what is possible. */
public final class CaptureOptions {
    /*
     * The uploader keeps one burst in flight and one waiting; a frame beyond what it takes is read
     * out, processed and dropped all the same (battery and heat, issue 26). So the camera repeats
     * its burst about as often as the uploader sends one (docs/android.md, "Benchmark", 50 Mbit/s).
     */
    /**
     * Live screens, pose frames alone (a one-beacon map): a pose window's round trip is 25-45 ms,
     * and a fix every 100 ms is all a walker needs (14 cm at 1.4 m/s); 60 a second was 6 times that.
     */
    public static final double LIVE_BURSTS_PER_S = 10.0;
    /**
     * Live screens, bursts with ID frames: four ID windows and a pose window take 0.25 s at 3 m,
     * 0.4 s at 2 m, 1 s at 1 m, so 5 a second is what the uploader takes at best; a burst that
     * waits is then at most 0.2 s old. (The protocol's captures are 0.5 s apart, docs/vlc.md.)
     */
    public static final double LIVE_ID_BURSTS_PER_S = 5.0;
    /**
     * The still screens (calibration, survey): their preview is drawn five times a second and the
     * shutter takes the next frame, so a fifth of a second is all the wait there is.
     */
    public static final double STILL_BURSTS_PER_S = 5.0;

    /** Exposure of the pose frames, ns. */
    public final long poseExposureNs;
    /** Exposure of the beacon-ID frames, ns; 0 = no ID frames. */
    public final long idExposureNs;
    /** Beacons in the map: ID frames are only worth taking when there is more than one to tell apart. */
    public final int beaconsInMap;
    /** Map ceiling height minus the phone's height above the floor, m: where to focus. */
    public final double ceilingDistanceM;
    /** Upper bound on output width x height (upload size and server time grow with it). */
    public final long maxPixels;
    /** The most bursts a second when a burst is a pose frame alone; the plan's last frame blanks the rest. */
    public final double burstsPerSecond;
    /** The same when a burst is a pose frame and its ID frames. */
    public final double idBurstsPerSecond;

    /** A live screen's options: {@link #LIVE_BURSTS_PER_S} and {@link #LIVE_ID_BURSTS_PER_S}. */
    public CaptureOptions(long poseExposureNs, long idExposureNs, int beaconsInMap, double ceilingDistanceM,
                          long maxPixels) {
        this(poseExposureNs, idExposureNs, beaconsInMap, ceilingDistanceM, maxPixels, LIVE_BURSTS_PER_S,
                LIVE_ID_BURSTS_PER_S);
    }

    private CaptureOptions(long poseExposureNs, long idExposureNs, int beaconsInMap, double ceilingDistanceM,
                           long maxPixels, double burstsPerSecond, double idBurstsPerSecond) {
        if (poseExposureNs <= 0) {
            throw new IllegalArgumentException("pose exposure must be > 0 ns, got " + poseExposureNs);
        }
        if (idExposureNs < 0) {
            throw new IllegalArgumentException("ID exposure must be >= 0 ns (0 = no ID frames), got " + idExposureNs);
        }
        if (beaconsInMap < 0) {
            throw new IllegalArgumentException("beacons in map must be >= 0, got " + beaconsInMap);
        }
        if (!(ceilingDistanceM > 0) || Double.isInfinite(ceilingDistanceM)) {
            throw new IllegalArgumentException("ceiling distance must be > 0 m, got " + ceilingDistanceM);
        }
        if (maxPixels <= 0) {
            throw new IllegalArgumentException("max pixels must be > 0, got " + maxPixels);
        }
        requireRate(burstsPerSecond);
        requireRate(idBurstsPerSecond);
        this.poseExposureNs = poseExposureNs;
        this.idExposureNs = idExposureNs;
        this.beaconsInMap = beaconsInMap;
        this.ceilingDistanceM = ceilingDistanceM;
        this.maxPixels = maxPixels;
        this.burstsPerSecond = burstsPerSecond;
        this.idBurstsPerSecond = idBurstsPerSecond;
    }

    /** The same options at other rates: pose frames alone, and bursts with ID frames, a second at most. */
    public CaptureOptions withBurstsPerSecond(double poseAlone, double withIdFrames) {
        return new CaptureOptions(poseExposureNs, idExposureNs, beaconsInMap, ceilingDistanceM, maxPixels, poseAlone,
                withIdFrames);
    }

    static double requireRate(double burstsPerSecond) {
        if (!(burstsPerSecond > 0) || Double.isInfinite(burstsPerSecond)) {
            throw new IllegalArgumentException("bursts per second must be > 0, got " + burstsPerSecond);
        }
        return burstsPerSecond;
    }

    /**
     * The capture protocol's exposures (shared_schemas/capture_protocol.json): the pose frame a
     * whole number of messages long, ID frames at the server's short exposure when {@code readBeaconIds}.
     */
    public static CaptureOptions fromProtocol(boolean readBeaconIds, int beaconsInMap, double ceilingDistanceM,
                                              long maxPixels) {
        return new CaptureOptions(CaptureProtocol.POSE_EXPOSURE_NS, readBeaconIds ? CaptureProtocol.ID_EXPOSURE_NS : 0,
                beaconsInMap, ceilingDistanceM, maxPixels);
    }

    /** ID frames are asked for and there is more than one beacon to tell apart. */
    public boolean wantsIdFrames() {
        return idExposureNs > 0 && beaconsInMap > 1;
    }
}
