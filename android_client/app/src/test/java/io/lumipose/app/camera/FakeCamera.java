package io.lumipose.app.camera;

import static org.robolectric.Shadows.shadowOf;

import android.content.Context;
import android.graphics.ImageFormat;
import android.graphics.Rect;
import android.hardware.camera2.CameraCharacteristics;
import android.hardware.camera2.CameraManager;
import android.hardware.camera2.CaptureRequest;
import android.hardware.camera2.CaptureResult;
import android.hardware.camera2.TotalCaptureResult;
import android.hardware.camera2.params.StreamConfiguration;
import android.hardware.camera2.params.StreamConfigurationDuration;
import android.hardware.camera2.params.StreamConfigurationMap;
import android.os.Looper;
import android.util.Range;
import android.util.Size;
import android.util.SizeF;

import java.lang.reflect.Constructor;
import java.util.ArrayList;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONException;
import org.json.JSONObject;
import org.robolectric.shadows.ShadowCameraCharacteristics;
import org.robolectric.shadows.ShadowCaptureResult;
import org.robolectric.shadows.ShadowTotalCaptureResult;
import org.robolectric.util.ReflectionHelpers;

import io.lumipose.client.camera.ArrayRect;
import io.lumipose.client.camera.Camera2Names;
import io.lumipose.client.camera.CameraFacts;

/**
 * A camera for the app's code under Robolectric: characteristics made from the core's
 * {@link CameraFacts} (so what {@code CameraFactsReader} reads back can be compared), and, once
 * the app has started its repeating burst, answers to each of its requests as a camera that
 * honours them would give: a TotalCaptureResult echoing the request (with its tag, which
 * Robolectric's results lack) and a padded YUV_420_888 image, delivered on the app's camera
 * thread in the order a test asks. Needs the three small shadows of {@link #SHADOWS}: a repeating
 * burst, YUV images and the characteristics' result keys, which Robolectric's own lack.
 */
public final class FakeCamera {
    /** The shadows a test that runs the camera declares in its {@code @Config(shadows = ...)}. */
    public static final Class<?>[] SHADOWS = {ShadowBurstSession.class, ShadowYuvImageReader.class,
            ShadowResultKeysCharacteristics.class};
    /** Rolling-shutter skew the fake camera reports: a 10 ms readout. */
    public static final long SKEW_NS = 10_000_000L;
    /** Bytes of padding at the end of each Y row. */
    public static final int ROW_PADDING = 64;

    private final CameraFacts facts;
    private long nextTimestampNs = 1_000_000_000L;
    /** CONTROL_AWB_STATE the results report from now on (searching until a test says otherwise). */
    private volatile int awbState = CaptureResult.CONTROL_AWB_STATE_SEARCHING;

    private FakeCamera(CameraFacts facts) {
        this.facts = facts;
    }

    /** Adds a camera with these facts to the context's CameraManager. */
    public static FakeCamera install(Context context, CameraFacts facts) {
        ShadowBurstSession.reset(); // a session of an earlier test is not this camera's
        ShadowYuvImageReader.reset();
        ShadowResultKeysCharacteristics.reset();
        CameraManager manager = (CameraManager) context.getSystemService(Context.CAMERA_SERVICE);
        shadowOf(manager).addCamera(facts.cameraId, characteristics(facts));
        return new FakeCamera(facts);
    }

    public CameraFacts facts() {
        return facts;
    }

    public void awbState(int state) {
        awbState = state;
    }

    /** Waits (up to {@code timeoutMs}) for the app to start a repeating burst; the session's shadow. */
    public ShadowBurstSession awaitBurst(long timeoutMs) throws InterruptedException {
        long end = System.currentTimeMillis() + timeoutMs;
        for (ShadowBurstSession s; System.currentTimeMillis() < end; Thread.sleep(5)) {
            shadowOf(Looper.getMainLooper()).idle();
            s = ShadowBurstSession.latest();
            if (s != null && !s.burst().isEmpty()) {
                idle(s); // the rest of onConfigured (the sink) runs after the burst starts
                return s;
            }
        }
        throw new AssertionError("the app started no repeating burst within " + timeoutMs + " ms");
    }

    /**
     * Captures the burst's request {@code index} once: its result and its image (luma of the
     * output's size, from {@code luma}) on the camera thread, the image first when asked. Waits
     * until the camera thread has handled both.
     */
    public long capture(ShadowBurstSession s, int index, byte[] luma, int width, int height, boolean imageFirst) {
        long timestamp = nextTimestampNs;
        nextTimestampNs += 33_000_000L;
        CaptureRequest request = s.burst().get(index);
        deliver(s, request, result(request, timestamp), luma, width, height, imageFirst);
        return timestamp;
    }

    /**
     * Captures a recorded frame for the burst's request {@code index}: its pixels and the result
     * the recording says the camera reported ({@code FrameResult} JSON, the simulator's phone).
     */
    public void capture(ShadowBurstSession s, int index, byte[] luma, int width, int height, JSONObject recorded)
            throws JSONException {
        CaptureRequest request = s.burst().get(index);
        deliver(s, request, recordedResult(request, recorded), luma, width, height, false);
    }

    private void deliver(ShadowBurstSession s, final CaptureRequest request, final TotalCaptureResult result,
                         byte[] luma, int width, int height, boolean imageFirst) {
        long timestamp = result.get(CaptureResult.SENSOR_TIMESTAMP);
        YuvImage image = new YuvImage(width, height, width + ROW_PADDING, timestamp, luma);
        ShadowYuvImageReader reader = ShadowYuvImageReader.latest();
        final ShadowBurstSession session = s;
        Runnable completed = new Runnable() {
            @Override
            public void run() {
                session.callback().onCaptureCompleted(session.session(), request, result);
            }
        };
        if (imageFirst) {
            reader.deliver(image);
            s.handler().post(completed);
        } else {
            s.handler().post(completed);
            reader.deliver(image);
        }
        idle(s);
    }

    /** Runs what is queued on the camera thread, from the test thread. */
    public static void idle(ShadowBurstSession s) {
        shadowOf(s.handler().getLooper()).idle();
    }

    /** What a camera that honours the request reports for it. */
    public TotalCaptureResult result(CaptureRequest request, long timestampNs) {
        TotalCaptureResult r = ShadowTotalCaptureResult.newTotalCaptureResult();
        ShadowCaptureResult shadow = (ShadowCaptureResult) org.robolectric.shadow.api.Shadow.extract(r);
        shadow.set(CaptureResult.SENSOR_TIMESTAMP, timestampNs);
        shadow.set(CaptureResult.SENSOR_EXPOSURE_TIME, request.get(CaptureRequest.SENSOR_EXPOSURE_TIME));
        shadow.set(CaptureResult.SENSOR_SENSITIVITY, request.get(CaptureRequest.SENSOR_SENSITIVITY));
        shadow.set(CaptureResult.SENSOR_FRAME_DURATION, request.get(CaptureRequest.SENSOR_FRAME_DURATION));
        shadow.set(CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW, SKEW_NS);
        shadow.set(CaptureResult.CONTROL_AWB_STATE, awbState);
        shadow.set(CaptureResult.LENS_FOCAL_LENGTH, (float) facts.availableFocalLengthsMm()[0]);
        shadow.set(CaptureResult.LENS_FOCUS_DISTANCE, request.get(CaptureRequest.LENS_FOCUS_DISTANCE));
        shadow.set(CaptureResult.SCALER_CROP_REGION, request.get(CaptureRequest.SCALER_CROP_REGION));
        shadow.set(CaptureResult.LENS_OPTICAL_STABILIZATION_MODE,
                request.get(CaptureRequest.LENS_OPTICAL_STABILIZATION_MODE));
        shadow.set(CaptureResult.TONEMAP_MODE, request.get(CaptureRequest.TONEMAP_MODE));
        shadow.set(CaptureResult.DISTORTION_CORRECTION_MODE, request.get(CaptureRequest.DISTORTION_CORRECTION_MODE));
        if (facts.lensIntrinsicCalibration() != null) {
            shadow.set(CaptureResult.LENS_INTRINSIC_CALIBRATION, floats(facts.lensIntrinsicCalibration()));
        }
        if (facts.lensDistortion() != null) {
            shadow.set(CaptureResult.LENS_DISTORTION, floats(facts.lensDistortion()));
        }
        // Robolectric's results carry no request; a camera's always do (the app reads its tag).
        ReflectionHelpers.setField(android.hardware.camera2.CaptureResult.class, r, "mRequest", request);
        return r;
    }

    /** A result of {@code request} saying what a recorded FrameResult JSON says. */
    public static TotalCaptureResult recordedResult(CaptureRequest request, JSONObject f) throws JSONException {
        TotalCaptureResult r = ShadowTotalCaptureResult.newTotalCaptureResult();
        ShadowCaptureResult shadow = (ShadowCaptureResult) org.robolectric.shadow.api.Shadow.extract(r);
        shadow.set(CaptureResult.SENSOR_TIMESTAMP, f.getLong("sensor_timestamp_ns"));
        shadow.set(CaptureResult.SENSOR_EXPOSURE_TIME, f.getLong("sensor_exposure_time_ns"));
        shadow.set(CaptureResult.SENSOR_SENSITIVITY, f.getInt("sensor_sensitivity"));
        shadow.set(CaptureResult.SENSOR_FRAME_DURATION, f.getLong("sensor_frame_duration_ns"));
        if (f.has("sensor_rolling_shutter_skew_ns")) {
            shadow.set(CaptureResult.SENSOR_ROLLING_SHUTTER_SKEW, f.getLong("sensor_rolling_shutter_skew_ns"));
        }
        shadow.set(CaptureResult.LENS_FOCAL_LENGTH, (float) f.getDouble("lens_focal_length_mm"));
        shadow.set(CaptureResult.LENS_INTRINSIC_CALIBRATION, floats(f.getJSONArray("lens_intrinsic_calibration")));
        shadow.set(CaptureResult.LENS_DISTORTION, floats(f.getJSONArray("lens_distortion")));
        JSONArray crop = f.getJSONArray("scaler_crop_region");
        shadow.set(CaptureResult.SCALER_CROP_REGION, new Rect(crop.getInt(0), crop.getInt(1),
                crop.getInt(0) + crop.getInt(2), crop.getInt(1) + crop.getInt(3)));
        shadow.set(CaptureResult.LENS_OPTICAL_STABILIZATION_MODE,
                code(Camera2Names::oisMode, f.getString("lens_optical_stabilization_mode")));
        shadow.set(CaptureResult.TONEMAP_MODE, code(Camera2Names::tonemapMode, f.getString("tonemap_mode")));
        shadow.set(CaptureResult.LENS_FOCUS_DISTANCE, (float) f.getDouble("lens_focus_distance_diopters"));
        shadow.set(CaptureResult.DISTORTION_CORRECTION_MODE,
                code(Camera2Names::distortionCorrectionMode, f.getString("distortion_correction_mode")));
        ReflectionHelpers.setField(android.hardware.camera2.CaptureResult.class, r, "mRequest", request);
        return r;
    }

    private static float[] floats(JSONArray a) throws JSONException {
        float[] out = new float[a.length()];
        for (int i = 0; i < out.length; i++) {
            out[i] = (float) a.getDouble(i);
        }
        return out;
    }

    /** CameraCharacteristics saying what {@code facts} says, in Camera2's own types and codes. */
    public static CameraCharacteristics characteristics(CameraFacts f) {
        CameraCharacteristics cc = ShadowCameraCharacteristics.newCameraCharacteristics();
        ShadowCameraCharacteristics s = shadowOf(cc);
        put(s, CameraCharacteristics.LENS_FACING, code(Camera2Names::lensFacing, f.lensFacing));
        put(s, CameraCharacteristics.SENSOR_ORIENTATION, f.sensorOrientationDeg);
        put(s, CameraCharacteristics.REQUEST_AVAILABLE_CAPABILITIES, codes(Camera2Names::capability, f.capabilities));
        put(s, CameraCharacteristics.SYNC_MAX_LATENCY, f.syncMaxLatency);
        if (f.timestampSource != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_TIMESTAMP_SOURCE,
                    code(Camera2Names::timestampSource, f.timestampSource));
        }
        put(s, CameraCharacteristics.SENSOR_INFO_ACTIVE_ARRAY_SIZE, rect(f.activeArray));
        if (f.preCorrectionActiveArray != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_PRE_CORRECTION_ACTIVE_ARRAY_SIZE, rect(f.preCorrectionActiveArray));
        }
        if (f.pixelArray != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_PIXEL_ARRAY_SIZE, new Size(f.pixelArray.width, f.pixelArray.height));
        }
        put(s, CameraCharacteristics.SENSOR_INFO_PHYSICAL_SIZE,
                new SizeF((float) f.physicalWidthMm, (float) f.physicalHeightMm));
        put(s, CameraCharacteristics.LENS_INFO_AVAILABLE_FOCAL_LENGTHS, floats(f.availableFocalLengthsMm()));
        if (f.lensIntrinsicCalibration() != null) {
            put(s, CameraCharacteristics.LENS_INTRINSIC_CALIBRATION, floats(f.lensIntrinsicCalibration()));
        }
        if (f.lensDistortion() != null) {
            put(s, CameraCharacteristics.LENS_DISTORTION, floats(f.lensDistortion()));
        }
        if (f.minimumFocusDistanceDiopters != null) {
            put(s, CameraCharacteristics.LENS_INFO_MINIMUM_FOCUS_DISTANCE, f.minimumFocusDistanceDiopters.floatValue());
        }
        if (f.focusDistanceCalibration != null) {
            put(s, CameraCharacteristics.LENS_INFO_FOCUS_DISTANCE_CALIBRATION,
                    code(Camera2Names::focusDistanceCalibration, f.focusDistanceCalibration));
        }
        put(s, CameraCharacteristics.LENS_INFO_AVAILABLE_OPTICAL_STABILIZATION, codes(Camera2Names::oisMode, f.oisModes));
        put(s, CameraCharacteristics.TONEMAP_AVAILABLE_TONE_MAP_MODES, codes(Camera2Names::tonemapMode, f.tonemapModes));
        if (f.tonemapMaxCurvePoints != null) {
            put(s, CameraCharacteristics.TONEMAP_MAX_CURVE_POINTS, f.tonemapMaxCurvePoints);
        }
        put(s, CameraCharacteristics.EDGE_AVAILABLE_EDGE_MODES, codes(Camera2Names::edgeMode, f.edgeModes));
        put(s, CameraCharacteristics.NOISE_REDUCTION_AVAILABLE_NOISE_REDUCTION_MODES,
                codes(Camera2Names::noiseReductionMode, f.noiseReductionModes));
        put(s, CameraCharacteristics.DISTORTION_CORRECTION_AVAILABLE_MODES,
                codes(Camera2Names::distortionCorrectionMode, f.distortionCorrectionModes));
        if (f.exposureTimeMinNs != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_EXPOSURE_TIME_RANGE,
                    new Range<Long>(f.exposureTimeMinNs, f.exposureTimeMaxNs));
        }
        if (f.sensitivityMin != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_SENSITIVITY_RANGE,
                    new Range<Integer>(f.sensitivityMin, f.sensitivityMax));
        }
        if (f.maxFrameDurationNs != null) {
            put(s, CameraCharacteristics.SENSOR_INFO_MAX_FRAME_DURATION, f.maxFrameDurationNs);
        }
        put(s, CameraCharacteristics.SCALER_STREAM_CONFIGURATION_MAP, streams(f));
        return cc;
    }

    /** Sets a characteristic the facts have; leaves the ones they lack unset, as a camera without them would. */
    private static <T> void put(ShadowCameraCharacteristics s, CameraCharacteristics.Key<T> key, T value) {
        if (value != null) {
            s.set(key, value);
        }
    }

    /** The YUV_420_888 outputs and their minimum frame durations as Camera2's map. */
    private static StreamConfigurationMap streams(CameraFacts f) {
        List<StreamConfiguration> sizes = new ArrayList<StreamConfiguration>();
        List<StreamConfigurationDuration> durations = new ArrayList<StreamConfigurationDuration>();
        for (CameraFacts.YuvOutput o : f.yuvOutputs) {
            // Every camera also lists its sizes in the HAL's IMPLEMENTATION_DEFINED format (the map checks).
            for (int format : new int[] {ImageFormat.YUV_420_888, ImageFormat.PRIVATE}) {
                sizes.add(new StreamConfiguration(format, o.size.width, o.size.height, false));
                durations.add(new StreamConfigurationDuration(format, o.size.width, o.size.height,
                        o.minFrameDurationNs));
            }
        }
        // Hidden API whose arguments vary by SDK: the configurations and their minimum durations first, then
        // stall durations, other formats' (depth, dynamic depth, HEIC) and high-speed video (all empty here),
        // reprocessing (null) and flags (false).
        for (Constructor<?> c : StreamConfigurationMap.class.getConstructors()) {
            Class<?>[] types = c.getParameterTypes();
            if (types.length < 3 || types[0] != StreamConfiguration[].class) {
                continue;
            }
            Object[] args = new Object[types.length];
            args[0] = sizes.toArray(new StreamConfiguration[0]);
            args[1] = durations.toArray(new StreamConfigurationDuration[0]);
            for (int i = 2; i < types.length; i++) {
                args[i] = types[i].isArray() ? java.lang.reflect.Array.newInstance(types[i].getComponentType(), 0)
                        : types[i] == boolean.class ? Boolean.FALSE : null;
            }
            try {
                return (StreamConfigurationMap) c.newInstance(args);
            } catch (ReflectiveOperationException e) {
                throw new IllegalStateException("StreamConfigurationMap" + java.util.Arrays.toString(types), e);
            }
        }
        throw new IllegalStateException("no StreamConfigurationMap constructor of the expected shape in this SDK");
    }

    interface Namer {
        String name(int code);
    }

    /** Camera2's code for a CameraFacts name: the inverse of the core's Camera2Names. */
    static int code(Namer names, String name) {
        for (int c = 0; c < 64; c++) {
            if (names.name(c).equals(name)) {
                return c;
            }
        }
        throw new IllegalArgumentException("no Camera2 code for '" + name + "'");
    }

    static int[] codes(Namer names, List<String> list) {
        if (list == null) {
            return null;
        }
        int[] out = new int[list.size()];
        for (int i = 0; i < out.length; i++) {
            out[i] = code(names, list.get(i));
        }
        return out;
    }

    static Rect rect(ArrayRect r) {
        return new Rect(r.left, r.top, r.left + r.width, r.top + r.height);
    }

    static float[] floats(double[] v) {
        float[] out = new float[v.length];
        for (int i = 0; i < v.length; i++) {
            out[i] = (float) v[i];
        }
        return out;
    }
}
