package io.lumipose.client.capture;

import io.lumipose.client.protocol.CaptureProtocol;

/** What the user and the map ask of the capture; the camera's facts then decide what is possible. */
public final class CaptureOptions {
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

    public CaptureOptions(long poseExposureNs, long idExposureNs, int beaconsInMap, double ceilingDistanceM,
                          long maxPixels) {
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
        this.poseExposureNs = poseExposureNs;
        this.idExposureNs = idExposureNs;
        this.beaconsInMap = beaconsInMap;
        this.ceilingDistanceM = ceilingDistanceM;
        this.maxPixels = maxPixels;
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
