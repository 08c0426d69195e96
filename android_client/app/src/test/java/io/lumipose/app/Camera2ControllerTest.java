package io.lumipose.app;

import static org.junit.Assert.assertArrayEquals;
import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertFalse;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertNotSame;
import static org.junit.Assert.assertNull;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Application;
import android.hardware.camera2.CameraDevice;
import android.hardware.camera2.CameraMetadata;
import android.hardware.camera2.CaptureRequest;
import android.hardware.camera2.params.TonemapCurve;
import android.os.Looper;

import java.nio.ByteBuffer;
import java.util.ArrayList;
import java.util.Collections;
import java.util.List;
import java.util.concurrent.CopyOnWriteArrayList;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.After;
import org.junit.Before;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.annotation.Config;
import org.robolectric.shadows.ShadowLooper;
import org.robolectric.util.ReflectionHelpers;

import io.lumipose.app.camera.FakeCamera;
import io.lumipose.app.camera.ShadowBurstSession;
import io.lumipose.app.camera.ShadowResultKeysCharacteristics;
import io.lumipose.app.camera.ShadowYuvImageReader;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.RequestSpec;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.protocol.CaptureProtocol;

/**
 * Camera2Controller against Robolectric's Camera2 framework classes (and the two small shadows in
 * {@code camera/}): the requests it builds are the capture protocol's, frames reach the sink as a
 * phone delivers them, and nothing that goes wrong on the camera thread ends the app. On the
 * minSdk's framework (28) and the compileSdk's (29).
 */
@RunWith(RobolectricTestRunner.class)
@Config(sdk = {28, 29}, shadows = {ShadowBurstSession.class, ShadowYuvImageReader.class, ShadowResultKeysCharacteristics.class})
public class Camera2ControllerTest {
    private static final long TIMEOUT_MS = 5000;
    private Application app;
    private FakeCamera camera;
    private final Recorder listener = new Recorder();
    private final List<Camera2Controller> controllers = new ArrayList<Camera2Controller>();

    /** Each test's camera closed and its thread ended, as a screen's onPause does. */
    @After
    public void stopCameras() {
        for (Camera2Controller c : controllers) {
            c.stop();
        }
    }

    /** What the controller told its listener, and the sink it was given. */
    static final class Recorder implements Camera2Controller.Listener {
        final List<String> events = new CopyOnWriteArrayList<String>();
        final List<FrameResult> results = new CopyOnWriteArrayList<FrameResult>();
        final List<byte[]> images = new CopyOnWriteArrayList<byte[]>();
        final List<int[]> strides = new CopyOnWriteArrayList<int[]>();
        volatile CapturePlan plan;
        volatile CameraFacts facts;
        volatile RuntimeException failWith;
        /** Planning fails this many times first (a camera busy when the screen opens fails the same way). */
        volatile int planFailures;
        int sinksMade;

        @Override
        public CapturePlan plan(CameraFacts f, CapturePlan positioning) {
            if (planFailures > 0) {
                planFailures--;
                throw new IllegalStateException("camera busy");
            }
            return positioning;
        }

        @Override
        public FrameSink onStarted(CameraFacts f, CapturePlan p, String summary) {
            facts = f;
            plan = p;
            sinksMade++;
            events.add("started");
            return new FrameSink() {
                @Override
                public void onResult(FrameResult result) {
                    if (failWith != null) {
                        throw failWith;
                    }
                    results.add(result);
                }

                @Override
                public void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                                    int pixelStride) {
                    if (failWith != null) {
                        throw failWith;
                    }
                    byte[] copy = new byte[width * height];
                    for (int row = 0; row < height; row++) {
                        for (int x = 0; x < width; x++) {
                            copy[row * width + x] = yPlane.get(row * rowStride + x * pixelStride);
                        }
                    }
                    images.add(copy);
                    strides.add(new int[] {rowStride, pixelStride});
                }
            };
        }

        @Override
        public void onUnsupported(String reason) {
            events.add("unsupported: " + reason);
        }

        @Override
        public void onCameraLost(String message, long retryInMs) {
            events.add("lost: " + message + " / " + retryInMs);
        }

        @Override
        public void onCameraBack(String summary) {
            events.add("back");
        }

        @Override
        public void onFrameError(String message) {
            events.add("frame error: " + message);
        }
    }

    @Before
    public void setUp() {
        app = RuntimeEnvironment.getApplication();
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        camera = FakeCamera.install(app, Devices.load(Devices.PRE_CORRECTION));
    }

    private Camera2Controller start(int beacons) {
        CaptureOptions options = new CaptureOptions(CaptureProtocol.POSE_EXPOSURE_NS, CaptureProtocol.ID_EXPOSURE_NS,
                beacons, 2.5, 2_000_000L);
        Camera2Controller c = new Camera2Controller(app, "", options, listener);
        controllers.add(c);
        c.start();
        return c;
    }

    private static byte[] pattern(int width, int height, int seed) {
        byte[] luma = new byte[width * height];
        for (int i = 0; i < luma.length; i++) {
            luma[i] = (byte) ((i * 31 + seed * 7) & 0xFF);
        }
        return luma;
    }

    @Test
    public void readsTheCameraAsTheCoreDescribesIt() throws Exception {
        start(4);
        camera.awaitBurst(TIMEOUT_MS);
        assertSameJson("", camera.facts().toJson(), listener.facts.toJson());
    }

    /** Equal JSON, numbers within a float's precision (Camera2 keeps floats where the core keeps doubles). */
    private static void assertSameJson(String path, Object expected, Object actual) {
        if (expected instanceof JSONObject) {
            JSONObject e = (JSONObject) expected;
            JSONObject a = (JSONObject) actual;
            assertEquals(path, e.keySet(), a.keySet());
            for (String k : e.keySet()) {
                assertSameJson(path + "." + k, e.opt(k), a.opt(k));
            }
        } else if (expected instanceof JSONArray) {
            JSONArray e = (JSONArray) expected;
            JSONArray a = (JSONArray) actual;
            assertEquals(path, e.length(), a.length());
            for (int i = 0; i < e.length(); i++) {
                assertSameJson(path + "[" + i + "]", e.opt(i), a.opt(i));
            }
        } else if (expected instanceof Number) {
            double e = ((Number) expected).doubleValue();
            assertEquals(path, e, ((Number) actual).doubleValue(), 1e-6 * Math.max(1, Math.abs(e)));
        } else {
            assertEquals(path, expected, actual);
        }
    }

    @Test
    public void buildsTheProtocolsRequests() throws Exception {
        start(4);
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        CapturePlan plan = listener.plan;
        List<CaptureRequest> burst = s.burst();
        assertEquals(1 + plan.idFramesPerBurst, burst.size());
        assertTrue("four panels: ID frames follow the pose frame " + plan.notes, plan.idFramesPerBurst > 0);
        for (int i = 0; i < burst.size(); i++) {
            CaptureRequest r = burst.get(i);
            RequestSpec spec = plan.burst().get(i);
            assertEquals(i == 0 ? RequestSpec.POSE : RequestSpec.ID, r.getTag());
            assertEquals(CameraMetadata.CONTROL_AE_MODE_OFF, (int) r.get(CaptureRequest.CONTROL_AE_MODE));
            assertEquals(CameraMetadata.CONTROL_AF_MODE_OFF, (int) r.get(CaptureRequest.CONTROL_AF_MODE));
            assertEquals(spec.exposureNs, (long) r.get(CaptureRequest.SENSOR_EXPOSURE_TIME));
            assertEquals(spec.frameDurationNs, (long) r.get(CaptureRequest.SENSOR_FRAME_DURATION));
            assertEquals(CameraMetadata.LENS_OPTICAL_STABILIZATION_MODE_OFF,
                    (int) r.get(CaptureRequest.LENS_OPTICAL_STABILIZATION_MODE));
            assertEquals(CameraMetadata.EDGE_MODE_OFF, (int) r.get(CaptureRequest.EDGE_MODE));
            assertEquals(CameraMetadata.NOISE_REDUCTION_MODE_OFF, (int) r.get(CaptureRequest.NOISE_REDUCTION_MODE));
            assertEquals(CameraMetadata.DISTORTION_CORRECTION_MODE_OFF,
                    (int) r.get(CaptureRequest.DISTORTION_CORRECTION_MODE));
            assertEquals(CameraMetadata.CONTROL_VIDEO_STABILIZATION_MODE_OFF,
                    (int) r.get(CaptureRequest.CONTROL_VIDEO_STABILIZATION_MODE));
            assertEquals(CameraMetadata.TONEMAP_MODE_CONTRAST_CURVE, (int) r.get(CaptureRequest.TONEMAP_MODE));
            TonemapCurve curve = r.get(CaptureRequest.TONEMAP_CURVE);
            assertNotNull(curve);
            float[] green = new float[2 * curve.getPointCount(TonemapCurve.CHANNEL_GREEN)];
            curve.copyColorCurve(TonemapCurve.CHANNEL_GREEN, green, 0);
            assertArrayEquals(spec.toneCurve(), green, 0f);
        }
        CaptureRequest pose = burst.get(0);
        assertEquals(CaptureProtocol.POSE_EXPOSURE_NS, (long) pose.get(CaptureRequest.SENSOR_EXPOSURE_TIME));
        assertEquals("the lowest ISO", camera.facts().sensitivityMin, pose.get(CaptureRequest.SENSOR_SENSITIVITY));
        assertEquals(CaptureProtocol.ID_EXPOSURE_NS, (long) burst.get(1).get(CaptureRequest.SENSOR_EXPOSURE_TIME));
    }

    @Test
    public void locksWhiteBalanceOnlyOnceItHasSettled() throws Exception {
        start(1);
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        assertFalse(s.burst().get(0).get(CaptureRequest.CONTROL_AWB_LOCK));
        assertEquals(CameraMetadata.CONTROL_AWB_MODE_AUTO, (int) s.burst().get(0).get(CaptureRequest.CONTROL_AWB_MODE));
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        for (int i = 0; i < Camera2Controller.AWB_SETTLE_MAX_FRAMES - 1; i++) {
            camera.capture(s, 0, pattern(w, h, i), w, h, false);
        }
        assertFalse("not before it settles", s.burst().get(0).get(CaptureRequest.CONTROL_AWB_LOCK));
        camera.capture(s, 0, pattern(w, h, 99), w, h, false);
        assertTrue("locked after the settling frames", s.burst().get(0).get(CaptureRequest.CONTROL_AWB_LOCK));
    }

    @Test
    public void locksWhiteBalanceAsSoonAsTheCameraSaysItConverged() throws Exception {
        start(1);
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        camera.capture(s, 0, pattern(w, h, 1), w, h, false);
        assertFalse("searching", s.burst().get(0).get(CaptureRequest.CONTROL_AWB_LOCK));
        camera.awbState(CameraMetadata.CONTROL_AWB_STATE_CONVERGED);
        camera.capture(s, 0, pattern(w, h, 2), w, h, false);
        assertTrue("converged: locked", s.burst().get(0).get(CaptureRequest.CONTROL_AWB_LOCK));
    }

    @Test
    public void deliversPaddedYuvImagesWithTheirResults() throws Exception {
        start(4);
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        byte[] first = pattern(w, h, 1);
        byte[] second = pattern(w, h, 2);
        long t1 = camera.capture(s, 0, first, w, h, false);
        long t2 = camera.capture(s, 1, second, w, h, true);
        assertEquals(2, listener.images.size());
        assertArrayEquals(first, listener.images.get(0));
        assertArrayEquals(second, listener.images.get(1));
        assertEquals(w + FakeCamera.ROW_PADDING, listener.strides.get(0)[0]);
        assertEquals(1, listener.strides.get(0)[1]);
        assertEquals(2, listener.results.size());
        FrameResult pose = listener.results.get(0);
        assertEquals(t1, pose.timestampNs);
        assertEquals(RequestSpec.POSE, pose.request);
        assertEquals(CaptureProtocol.POSE_EXPOSURE_NS, (long) pose.exposureNs);
        assertEquals(FakeCamera.SKEW_NS, (long) pose.rollingShutterSkewNs);
        assertEquals(RequestSpec.ID, listener.results.get(1).request);
        assertEquals(t2, listener.results.get(1).timestampNs);
        assertEquals("both images taken", 2, ShadowYuvImageReader.latest().acquired());
        assertEquals("every image closed", 0, ShadowYuvImageReader.latest().open());
    }

    @Test
    public void aSinkThatThrowsDropsTheFrameNotTheApp() throws Exception {
        start(1);
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        listener.failWith = new IllegalStateException("bug in the sink");
        camera.capture(s, 0, pattern(w, h, 1), w, h, false);
        camera.capture(s, 0, pattern(w, h, 2), w, h, true);
        List<String> errors = new ArrayList<String>();
        for (String e : listener.events) {
            if (e.startsWith("frame error")) {
                errors.add(e);
            }
        }
        assertEquals("told once, not every frame: " + listener.events, 1, errors.size());
        assertTrue(errors.get(0), errors.get(0).contains("bug in the sink"));
        listener.failWith = null;
        byte[] next = pattern(w, h, 3);
        camera.capture(s, 0, next, w, h, false);
        assertArrayEquals("the camera thread lives on", next, listener.images.get(listener.images.size() - 1));
    }

    @Test
    public void aLostCameraIsOpenedAgainIntoTheSameSink() throws Exception {
        start(1);
        ShadowBurstSession first = camera.awaitBurst(TIMEOUT_MS);
        // Another app takes the camera: Camera2 tells the device's state callback.
        Looper cameraLooper = first.handler().getLooper();
        CameraDevice device = first.session().getDevice();
        ShadowBurstSession.reset();
        shadowOf(app.getSystemService(android.hardware.camera2.CameraManager.class)).triggerDisconnect();
        shadowOf(Looper.getMainLooper()).idle();
        shadowOf(cameraLooper).idle();
        assertTrue(listener.events.toString(), listener.events.get(listener.events.size() - 1)
                .startsWith("lost: Camera disconnected"));
        assertTrue("the session went with the device", first.closed());
        ShadowLooper looper = shadowOf(cameraLooper);
        looper.idleFor(java.time.Duration.ofMillis(Camera2Controller.FIRST_RETRY_MS));
        ShadowBurstSession second = camera.awaitBurst(TIMEOUT_MS);
        assertNotSame(first, second);
        assertNotNull(device);
        assertEquals("back", listener.events.get(listener.events.size() - 1));
        assertEquals("one sink across the reopening", 1, listener.sinksMade);
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        byte[] frame = pattern(w, h, 5);
        camera.capture(second, 0, frame, w, h, false);
        assertArrayEquals(frame, listener.images.get(listener.images.size() - 1));
    }

    @Test
    public void aCameraLostBeforeItsFirstFramesStillGetsItsSink() throws Exception {
        listener.planFailures = 1;
        start(1);
        for (int i = 0; i < 200 && listener.events.isEmpty(); i++) {
            Thread.sleep(10);
        }
        assertTrue(listener.events.toString(), listener.events.get(0).startsWith("lost: Camera failed to open"));
        // the retry, a second later on the camera thread's clock
        Looper cameraLooper = ReflectionHelpers.<android.os.Handler>getField(controllers.get(0), "handler").getLooper();
        shadowOf(cameraLooper).idleFor(java.time.Duration.ofMillis(Camera2Controller.FIRST_RETRY_MS));
        ShadowBurstSession s = camera.awaitBurst(TIMEOUT_MS);
        assertEquals(listener.events.toString(), "started", listener.events.get(listener.events.size() - 1));
        int w = listener.plan.output.width;
        int h = listener.plan.output.height;
        byte[] frame = pattern(w, h, 7);
        camera.capture(s, 0, frame, w, h, false);
        assertArrayEquals("frames reach the screen", frame, listener.images.get(0));
    }

    @Test
    public void withoutThePermissionItSaysSo() throws Exception {
        shadowOf(app).denyPermissions(Manifest.permission.CAMERA);
        Camera2Controller c = start(1);
        for (int i = 0; i < 100 && listener.events.isEmpty(); i++) {
            Thread.sleep(10);
        }
        assertEquals(Collections.singletonList("unsupported: Camera permission not granted."), listener.events);
        c.stop();
        assertNull(ShadowBurstSession.latest());
    }
}
