package io.lumipose.client.capture;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.camera.IntrinsicsCalculator;
import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.sensor.GravityTransform;
import io.lumipose.client.sensor.GyroTransform;
import io.lumipose.client.sensor.HeadingEstimator;
import io.lumipose.client.sensor.LensFacing;

/**
 * Turns one frame's capture result into its contract JSON, or says why the frame must not be sent.
 * A frame is what its result says, not what its request asked: unless SYNC_MAX_LATENCY is
 * PER_FRAME_CONTROL, a request's settings reach the sensor some frames later, so a frame tagged
 * "pose" can carry the ID exposure and the real pose frame a tag "id". Each frame is therefore
 * classified by the exposure and ISO in its result against the plan's two requests; one that
 * matches neither (settings in transition) is dropped, one whose tag disagrees is taken as its
 * result shows, with a warning.
 */
public final class FrameDescriber {
    /** Relative difference between asked and reported exposure or ISO still counted as "as asked". */
    public static final double TOLERANCE = 0.05;
    /** Crop-region rounding a HAL may do, px per edge. */
    private static final int CROP_TOLERANCE_PX = 2;

    /** One frame's verdict. */
    public static final class Described {
        /** The frame's JSON; null when dropped. */
        public final FrameMeta meta;
        /** "pose" or "id" as the result shows; null when it matches neither request. */
        public final String kind;
        /** Why the frame is not sent; null when kept. */
        public final String dropReason;
        public final List<String> warnings;

        Described(FrameMeta meta, String kind, String dropReason, List<String> warnings) {
            this.meta = meta;
            this.kind = kind;
            this.dropReason = dropReason;
            this.warnings = Collections.unmodifiableList(new ArrayList<String>(warnings));
        }

        public boolean kept() {
            return meta != null;
        }
    }

    private final CameraFacts facts;
    private final CapturePlan plan;
    private final Double mapXBearingDeg;
    private final DeviceProfile calibration;

    /**
     * @param mapXBearingDeg compass bearing of the map's +X axis (deg clockwise from north), or null
     *                       to send no heading
     */
    public FrameDescriber(CameraFacts facts, CapturePlan plan, Double mapXBearingDeg) {
        this(facts, plan, mapXBearingDeg, null);
    }

    /**
     * @param calibration this camera's calibrated profile (the "Calibrate camera" screen's), or null:
     *                    frames then carry its pinhole and distortion scaled to the output, instead of
     *                    what Camera2 reports, as long as the result's focal length is the profile's
     */
    public FrameDescriber(CameraFacts facts, CapturePlan plan, Double mapXBearingDeg, DeviceProfile calibration) {
        this.facts = facts;
        this.plan = plan;
        this.mapXBearingDeg = mapXBearingDeg;
        this.calibration = calibration;
    }

    /** {@link #describe(FrameResult, float[], float[], float[])} without a gyroscope reading. */
    public Described describe(FrameResult result, float[] gravityDevice, float[] deviceToEnu) {
        return describe(result, gravityDevice, deviceToEnu, null);
    }

    /**
     * @param gravityDevice TYPE_GRAVITY [x, y, z] at the frame's timestamp (see GravityHistory), or null
     * @param deviceToEnu   device-to-ENU rotation (row-major 3x3) at the frame's timestamp, or null
     * @param rateDevice    TYPE_GYROSCOPE [x, y, z], rad/s, the mean over the frame's readout (see
     *                      GyroHistory), or null
     */
    public Described describe(FrameResult result, float[] gravityDevice, float[] deviceToEnu, float[] rateDevice) {
        List<String> warnings = new ArrayList<String>();
        String kind = classify(result);
        if (kind == null) {
            return drop(null, "exposure " + result.exposureNs + " ns, ISO " + result.sensitivityIso
                    + " match neither the pose nor the ID request (settings in transition)", warnings);
        }
        if (result.request != null && !result.request.equals(kind)) {
            // The pixels were taken with the result's settings: the tag is only what was asked.
            warnings.add(settingsLagWarning());
        }
        RequestSpec spec = plan.spec(kind);
        if (result.cropRegion != null && !near(result.cropRegion, spec.cropRegion)) {
            return drop(kind, "SCALER_CROP_REGION " + result.cropRegion + " is not the requested "
                    + spec.cropRegion, warnings);
        }
        if (RequestSpec.ID.equals(kind) && result.rollingShutterSkewNs == null) {
            return drop(kind, "no rolling-shutter skew: beacon IDs off", warnings);
        }
        if (spec.oisOff && "on".equals(result.oisMode)) {
            warnings.add("optical stabilisation stayed on: the principal point may move");
        }
        Intrinsics camera;
        try {
            camera = calibrated(IntrinsicsCalculator.forFrame(facts, result, plan.output, warnings), warnings);
        } catch (IllegalArgumentException e) {
            return drop(kind, e.getMessage(), warnings);
        }
        try {
            return new Described(meta(result, kind, spec, camera, gravityDevice, deviceToEnu, rateDevice, warnings),
                    kind, null, warnings);
        } catch (IllegalArgumentException e) {
            return drop(kind, e.getMessage(), warnings); // a value the contract refuses, named
        }
    }

    /** The frame's JSON in the contract's units: exposure, ISO and skew as the result reports them. */
    private FrameMeta meta(FrameResult result, String kind, RequestSpec spec, Intrinsics camera, float[] gravityDevice,
                           float[] deviceToEnu, float[] rateDevice, List<String> warnings) {
        FrameMeta.Builder b = FrameMeta.builder(plan.output.width, plan.output.height)
                .rowStride(plan.output.width)
                .camera(camera)
                .timestampNs(result.timestampNs)
                .frameKind(kind)
                .extra("tone_curve", toneCurve(result, spec));
        if (result.exposureNs != null) {
            b.exposureS(result.exposureNs / 1e9);
        }
        if (result.sensitivityIso != null) {
            b.iso((double) result.sensitivityIso);
        }
        if (result.rollingShutterSkewNs != null) {
            b.rollingShutterSkewS(result.rollingShutterSkewNs / 1e9);
        }
        LensFacing facing = facts.facing();
        if (gravityDevice != null && facing != null) {
            try {
                b.gravityCamera(GravityTransform.deviceToCamera(gravityDevice, facts.sensorOrientationDeg, facing));
            } catch (IllegalArgumentException e) {
                warnings.add("gravity not sent: " + e.getMessage());
            }
        }
        if (rateDevice != null && facing != null) {
            double[] rate = GyroTransform.deviceToCameraDps(rateDevice, facts.sensorOrientationDeg, facing);
            try {
                // A wild reading costs the frame its rate, not the frame itself.
                b.angularVelocityCameraDps(ContractRanges.ANGULAR_RATE_DPS.checkEach("angular_velocity_camera_dps", rate));
            } catch (IllegalArgumentException e) {
                warnings.add("rotation rates beyond the contract's 4000 deg/s not sent"); // the same text: said once
            }
        }
        if (deviceToEnu != null && facing != null) {
            // Every frame says where its image's +x points on the compass (a survey measures the map's
            // bearing from it); the heading needs the map's bearing too.
            Double compass = HeadingEstimator.compassBearingDeg(deviceToEnu, facts.sensorOrientationDeg, facing);
            b.compassBearingDeg(compass);
            if (compass != null && mapXBearingDeg != null) {
                b.headingDeg(HeadingEstimator.headingDeg(mapXBearingDeg, compass));
            }
        }
        return b.build();
    }

    /**
     * The calibrated profile's pinhole at the output size in place of Camera2's; Camera2's when there
     * is no profile, or when the frame's lens is not the calibrated one (a logical multi-camera
     * switched lenses: its focal length differs by more than 1 %), with a warning.
     */
    private Intrinsics calibrated(Intrinsics reported, List<String> warnings) {
        if (calibration == null) {
            return reported;
        }
        if (reported.focalLengthM != null
                && Math.abs(reported.focalLengthM - calibration.focalLengthM) > 0.01 * calibration.focalLengthM) {
            warnings.add("calibration '" + calibration.id + "' not used: the frame's focal length "
                    + reported.focalLengthM * 1000 + " mm is not the calibrated " + calibration.focalLengthM * 1000
                    + " mm (another lens)");
            return reported;
        }
        return calibration.forFrame(plan.output.width, plan.output.height);
    }

    /**
     * "pose" or "id" by the result's exposure and ISO; null when it matches neither request.
     * A result without an exposure can only be trusted when there is one kind of frame.
     */
    String classify(FrameResult result) {
        if (result.exposureNs == null) {
            return plan.id == null ? RequestSpec.POSE : null;
        }
        if (matches(result, plan.pose)) {
            return RequestSpec.POSE;
        }
        return plan.id != null && matches(result, plan.id) ? RequestSpec.ID : null;
    }

    private static boolean matches(FrameResult result, RequestSpec spec) {
        boolean exposure = close(result.exposureNs, spec.exposureNs);
        boolean iso = spec.sensitivityIso == null || result.sensitivityIso == null
                || close(result.sensitivityIso, spec.sensitivityIso);
        return exposure && iso;
    }

    private static boolean close(double reported, double asked) {
        return Math.abs(reported - asked) <= TOLERANCE * asked;
    }

    /**
     * "linear" only when the device reports the contrast curve the plan asked for; "srgb" when it reports the sRGB
     * preset (a known curve, whoever asked for it); else "device".
     */
    static String toneCurve(FrameResult result, RequestSpec spec) {
        if (spec.linearToneCurve() && "contrast_curve".equals(result.tonemapMode)) {
            return "linear";
        }
        boolean srgb = "preset_curve".equals(result.tonemapMode) && "srgb".equals(result.tonemapPresetCurve);
        return srgb ? "srgb" : "device";
    }

    private static boolean near(ArrayRect a, ArrayRect b) {
        return Math.abs(a.left - b.left) <= CROP_TOLERANCE_PX && Math.abs(a.top - b.top) <= CROP_TOLERANCE_PX
                && Math.abs(a.left + a.width - b.left - b.width) <= CROP_TOLERANCE_PX
                && Math.abs(a.top + a.height - b.top - b.height) <= CROP_TOLERANCE_PX;
    }

    /** The same text for every such frame, so the pipeline shows it once. */
    private String settingsLagWarning() {
        String latency = CapturePlan.syncMaxLatencyName(facts.syncMaxLatency);
        String why = facts.hasPerFrameControl() ? ", although SYNC_MAX_LATENCY is " + latency
                : ": settings lag (SYNC_MAX_LATENCY " + latency + ")";
        return "frames came with another request's exposure than their own" + why
                + "; each is sent as its capture result shows";
    }

    private static Described drop(String kind, String reason, List<String> warnings) {
        return new Described(null, kind, reason, warnings);
    }
}
