package io.lumipose.client.replay;

import java.util.LinkedHashSet;
import java.util.List;
import java.util.Set;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.camera.IntrinsicsCalculator;
import io.lumipose.client.camera.PixelSize;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.json.Json;
import io.lumipose.client.sensor.GravityTransform;
import io.lumipose.client.sensor.GyroTransform;
import io.lumipose.client.sensor.LensFacing;

/**
 * The phone a recording was rendered for, as Camera2 would describe it: the CameraFacts JSON of
 * its camera, the FrameResult JSON of each frame and its TYPE_GRAVITY reading
 * ({@code docs/android.md}). Its characteristics give exactly the fixtures' camera: the pixel
 * array (= active = pre-correction array) is the largest frame, the calibration is the
 * fixture's in Camera2's convention, and focal length and physical size are the fixture's.
 */
public final class SimulatedPhone {
    /** The Mi 8's front camera, the profile the simulator renders. */
    public static final LensFacing FACING = LensFacing.FRONT;
    public static final int SENSOR_ORIENTATION_DEG = 270;
    /** The stream's minimum frame duration at every size: 30 fps. */
    static final long FRAME_DURATION_NS = 33333333L;

    private final PixelSize array;
    private final double pixelSizeM;
    private final double focalLengthM;
    /** Camera2's LENS_INTRINSIC_CALIBRATION: pixel centres at x + 0.5, as floats. */
    private final double[] calibration;
    /** Camera2's LENS_DISTORTION [k1, k2, k3, p1, p2], as floats. */
    private final double[] distortion;
    private final Set<PixelSize> outputs = new LinkedHashSet<PixelSize>();
    /** The recording's pose frames' ISO: the lowest this phone has, as the plan takes the lowest. */
    private final int lowestIso;
    private final int highestIso;
    private final long poseExposureNs;
    /** 0 when the recording has no ID frames. */
    private final long idExposureNs;
    /** Frames from a request to the frame its settings reach; 0: per-frame control. */
    public final int settingsLagFrames;

    public SimulatedPhone(List<RecordedFrame> frames) {
        this(frames, 0);
    }

    /**
     * @param settingsLagFrames 0 for a phone with per-frame control; else how many frames late a
     *                          request's settings reach the sensor (its SYNC_MAX_LATENCY is then unknown)
     */
    public SimulatedPhone(List<RecordedFrame> frames, int settingsLagFrames) {
        if (settingsLagFrames < 0) {
            throw new IllegalArgumentException("settingsLagFrames must be >= 0, got " + settingsLagFrames);
        }
        this.settingsLagFrames = settingsLagFrames;
        RecordedFrame largest = frames.get(0);
        for (RecordedFrame f : frames) {
            if ((long) f.width * f.height > (long) largest.width * largest.height) {
                largest = f;
            }
        }
        Intrinsics k = largest.camera;
        if (k.pixelSizeM == null || k.focalLengthM == null) {
            throw new IllegalArgumentException(largest.name + ": the camera needs pixel_size_m and focal_length_m "
                    + "to describe its lens and sensor");
        }
        array = new PixelSize(largest.width, largest.height);
        pixelSizeM = k.pixelSizeM;
        focalLengthM = k.focalLengthM;
        calibration = floats(k.fx, k.fy, k.cx + 0.5, k.cy + 0.5, 0);
        distortion = floats(camera2Distortion(k.distortion(), largest.name));
        int lowest = Integer.MAX_VALUE;
        int highest = 3200;
        long pose = 0;
        long id = 0;
        for (RecordedFrame f : frames) {
            checkSameCamera(f);
            outputs.add(new PixelSize(f.width, f.height));
            highest = Math.max(highest, iso(f));
            if (f.isIdFrame()) {
                id = exposureNs(f);
            } else {
                lowest = Math.min(lowest, iso(f));
                pose = exposureNs(f);
            }
        }
        if (pose == 0) {
            throw new IllegalArgumentException("the recording has no pose frame");
        }
        lowestIso = lowest;
        highestIso = highest;
        poseExposureNs = pose;
        idExposureNs = id;
    }

    private static int iso(RecordedFrame f) {
        return (int) Math.round(f.iso);
    }

    private static long exposureNs(RecordedFrame f) {
        return Math.round(f.exposureS * 1e9);
    }

    /**
     * What the user of this phone set: the recording's exposures (no ID frames when it has none),
     * its largest frame as the size limit.
     */
    public CaptureOptions captureOptions(int beaconsInMap, double ceilingDistanceM) {
        return new CaptureOptions(poseExposureNs, idExposureNs, beaconsInMap, ceilingDistanceM, array.pixels());
    }

    /** OpenCV (k1, k2, p1, p2[, k3]) to Camera2's [k1, k2, k3, p1, p2]. */
    private static double[] camera2Distortion(double[] d, String name) {
        if (d.length == 0) {
            return new double[5];
        }
        if (d.length != 4 && d.length != 5) {
            throw new IllegalArgumentException(name + ": Camera2 has no place for " + d.length
                    + " distortion coefficients (it takes k1, k2, k3, p1, p2)");
        }
        return new double[] {d[0], d[1], d.length == 5 ? d[4] : 0, d[2], d[3]};
    }

    /** Camera2 reports floats: the app sees these values, not the renderer's doubles. */
    private static double[] floats(double... values) {
        double[] out = new double[values.length];
        for (int i = 0; i < values.length; i++) {
            out[i] = (float) values[i];
        }
        return out;
    }

    /** A smaller output (an ID frame) must be this camera scaled, as a phone's stream would be. */
    private void checkSameCamera(RecordedFrame f) {
        float[] c = new float[calibration.length];
        for (int i = 0; i < c.length; i++) {
            c[i] = (float) calibration[i];
        }
        ArrayRect whole = ArrayRect.ofSize(array.width, array.height);
        Intrinsics expected = IntrinsicsCalculator.fromLensCalibration(c, whole, whole,
                new PixelSize(f.width, f.height), f.camera.distortion(), null);
        double tolerancePx = 1e-3;
        double off = Math.max(Math.max(Math.abs(expected.fx - f.camera.fx), Math.abs(expected.fy - f.camera.fy)),
                Math.max(Math.abs(expected.cx - f.camera.cx), Math.abs(expected.cy - f.camera.cy)));
        if (off > tolerancePx) {
            throw new IllegalArgumentException(f.name + ": its camera (fx " + f.camera.fx + ", cx " + f.camera.cx
                    + ") is not the recording's " + array + " camera scaled to " + f.width + "x" + f.height
                    + " (fx " + expected.fx + ", cx " + expected.cx + ")");
        }
    }

    /** SENSOR_INFO_ACTIVE_ARRAY_SIZE (= pixel array = pre-correction array). */
    public PixelSize pixelArray() {
        return array;
    }

    /** The CameraFacts JSON of the front camera (docs/android.md). */
    public JSONObject characteristics() {
        JSONObject o = new JSONObject();
        Json.put(o, "camera_id", "1");
        Json.put(o, "lens_facing", "front");
        Json.put(o, "sensor_orientation", SENSOR_ORIENTATION_DEG);
        Json.put(o, "capabilities", names("manual_sensor", "read_sensor_settings"));
        // A phone whose settings lag: Camera2 says "unknown" for most LIMITED devices.
        Json.put(o, "sync_max_latency", settingsLagFrames == 0 ? "per_frame_control" : "unknown");
        Json.put(o, "timestamp_source", "realtime");
        Json.put(o, "active_array", wholeArray());
        Json.put(o, "pre_correction_active_array", wholeArray());
        Json.put(o, "pixel_array", ints(array.width, array.height));
        Json.put(o, "physical_size_mm", Json.array(floats(array.width * pixelSizeM * 1e3,
                array.height * pixelSizeM * 1e3)));
        Json.put(o, "available_focal_lengths_mm", Json.array(floats(focalLengthM * 1e3)));
        Json.put(o, "lens_intrinsic_calibration", Json.array(calibration));
        Json.put(o, "lens_distortion", Json.array(distortion));
        // A fixed-focus front camera, as the Mi 8's.
        Json.put(o, "minimum_focus_distance_diopters", 0.0);
        Json.put(o, "focus_distance_calibration", "uncalibrated");
        Json.put(o, "ois_modes", names("off"));
        Json.put(o, "tonemap_modes", names("contrast_curve", "fast", "high_quality"));
        Json.put(o, "tonemap_max_curve_points", 64);
        Json.put(o, "edge_modes", names("off", "fast", "high_quality"));
        Json.put(o, "noise_reduction_modes", names("off", "fast", "high_quality"));
        Json.put(o, "distortion_correction_modes", names("off"));
        Json.put(o, "exposure_time_range_ns", ints(10000, 1000000000));
        Json.put(o, "sensitivity_range", ints(lowestIso, highestIso));
        Json.put(o, "max_frame_duration_ns", 1000000000L);
        JSONArray yuv = new JSONArray();
        for (PixelSize s : outputs) {
            yuv.put(ints(s.width, s.height, FRAME_DURATION_NS));
        }
        Json.put(o, "yuv_outputs", yuv);
        return o;
    }

    /**
     * The FrameResult JSON of a frame taken for {@code request}: the exposure and ISO the frame
     * was rendered with (what its pixels show), the request's other settings as applied.
     */
    public JSONObject result(RecordedFrame f, RequestSpec request) {
        return result(f, request, request);
    }

    /**
     * The FrameResult JSON of a frame whose settings came from {@code applied} (the frame's
     * rendered exposure and ISO, what its pixels show) while its tag is {@code tagged}'s, the
     * request submitted for this frame: they differ when the settings lag.
     */
    public JSONObject result(RecordedFrame f, RequestSpec applied, RequestSpec tagged) {
        JSONObject o = new JSONObject();
        Json.put(o, "sensor_timestamp_ns", f.timestampNs);
        Json.put(o, "request", tagged.kind);
        Json.put(o, "sensor_exposure_time_ns", exposureNs(f));
        Json.put(o, "sensor_sensitivity", iso(f));
        Json.put(o, "sensor_frame_duration_ns", applied.frameDurationNs);
        if (f.rollingShutterSkewS != null) {
            Json.put(o, "sensor_rolling_shutter_skew_ns", Math.round(f.rollingShutterSkewS * 1e9));
        }
        Json.put(o, "lens_focal_length_mm", (double) (float) (focalLengthM * 1e3));
        Json.put(o, "lens_intrinsic_calibration", Json.array(calibration));
        Json.put(o, "lens_distortion", Json.array(distortion));
        ArrayRect crop = applied.cropRegion;
        Json.put(o, "scaler_crop_region", ints(crop.left, crop.top, crop.width, crop.height));
        Json.put(o, "lens_optical_stabilization_mode", "off");  // the only mode this camera has
        Json.put(o, "tonemap_mode", applied.linearToneCurve() ? "contrast_curve" : applied.srgbPreset ? "preset_curve"
                : "fast");
        if (applied.srgbPreset) {
            Json.put(o, "tonemap_preset_curve", "srgb");
        }
        Json.put(o, "lens_focus_distance_diopters", 0.0);  // fixed focus
        Json.put(o, "distortion_correction_mode", "off");
        return o;
    }

    /** TYPE_GRAVITY [x, y, z] (m/s^2, device frame) of the phone when it took {@code f}, or null. */
    public float[] gravity(RecordedFrame f) {
        double[] g = f.gravityCamera();
        return g == null ? null : GravityTransform.cameraToDevice(g, SENSOR_ORIENTATION_DEG, FACING);
    }

    /** TYPE_GYROSCOPE [x, y, z] (rad/s, device frame) of the phone while it read {@code f} out, or null. */
    public float[] rotationRate(RecordedFrame f) {
        double[] w = f.angularVelocityCameraDps();
        return w == null ? null : GyroTransform.cameraDpsToDevice(w, SENSOR_ORIENTATION_DEG, FACING);
    }

    /** The Camera2 characteristics as the app reads them. */
    public CameraFacts facts() {
        return CameraFacts.fromJson(characteristics());
    }

    private JSONArray wholeArray() {
        return ints(0, 0, array.width, array.height);
    }

    private static JSONArray ints(long... values) {
        JSONArray a = new JSONArray();
        for (long v : values) {
            a.put(v);
        }
        return a;
    }

    private static JSONArray names(String... names) {
        JSONArray a = new JSONArray();
        for (String n : names) {
            a.put(n);
        }
        return a;
    }
}
