package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertFalse;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Application;
import android.widget.Button;

import java.io.IOException;
import java.util.concurrent.Callable;

import org.junit.After;
import org.junit.Before;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.android.controller.ActivityController;

import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.HttpCall;
import io.lumipose.client.net.HttpReply;
import io.lumipose.client.net.HttpTransport;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.net.Sleeper;

/**
 * Defect 1: the shutter works again after the screen was left with a shot armed, and after an
 * upload interrupted by the screen's executor shutting down. The camera is the test's: the screen's
 * own onStarted (what the camera thread calls once configured) and frames fed to its sink.
 */
@RunWith(RobolectricTestRunner.class)
public class ShutterTest {
    static final String SAMPLE = "{\"id\": \"s1\", \"label\": \"survey\", \"result\": {\"schema\": "
            + "\"lumipose.result/1\", \"ok\": false, \"reason\": \"beacon_id_unknown\"}}";
    private final Screens.Camera camera = new Screens.Camera();
    private FakeServer server;
    private Application app;

    @Before
    public void setUp() throws IOException {
        app = RuntimeEnvironment.getApplication();
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        server = new FakeServer().answer("POST /v1/samples", 201, SAMPLE);
        Screens.server(app, server.url());
    }

    @After
    public void tearDown() {
        server.close();
    }

    static String boardView(CapturePlan plan) {
        return "{\"name\": \"photo-1\", \"width\": " + plan.output.width + ", \"height\": " + plan.output.height
                + ", \"corner_ids\": [3, 4], \"corners_px\": [[5, 5], [60, 40]]}";
    }

    private void armLeaveAndComeBack(final StillActivity a, ActivityController<?> c, String upload) throws Exception {
        FrameSink sink = camera.start(a);
        final Button shutter = a.shutter;
        shutter.performClick();
        assertFalse("armed: off until the photo is handled", shutter.isEnabled());
        c.pause();
        c.resume();
        assertTrue("the armed shot was dropped with the camera: the shutter must work again", shutter.isEnabled());

        sink = camera.start(a); // the camera back
        shutter.performClick();
        assertFalse(shutter.isEnabled());
        camera.frame(a, sink, 7);
        Screens.settle("the photo handled", new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return shutter.isEnabled();
            }
        });
        assertEquals(1, server.requests(upload).size());
    }

    @Test
    public void surveyShutterWorksAfterLeavingWithAShotArmed() throws Exception {
        ActivityController<SurveyActivity> c = Robolectric.buildActivity(SurveyActivity.class).setup();
        armLeaveAndComeBack(c.get(), c, "POST /v1/samples");
    }

    @Test
    public void calibrationShutterWorksAfterLeavingWithAShotArmed() throws Exception {
        ActivityController<CameraCalibrationActivity> c = Robolectric.buildActivity(CameraCalibrationActivity.class)
                .setup();
        CameraCalibrationActivity a = c.get();
        server.answer("POST /v1/calibrations/views", 200, boardView(a.plan(camera.facts, camera.positioning)));
        armLeaveAndComeBack(a, c, "POST /v1/calibrations/views");
    }

    /** What an executor shut down mid-upload looks like to the upload: the thread interrupted. */
    static LumiposeClient interrupted() {
        return new LumiposeClient(new ClientConfig("http://127.0.0.1:1", "", "phone", false,
                new RetryPolicy(3, 1, 1.0, 1)), new HttpTransport() {
                    @Override
                    public HttpReply send(HttpCall call) throws IOException {
                        Screens.<RuntimeException>sneak(new InterruptedException("executor shut down"));
                        return null;
                    }
                }, Sleeper.REAL);
    }

    private void interruptedUpload(final StillActivity a) {
        a.client = interrupted(); // the session made at the first shot uses it
        FrameSink sink = camera.start(a);
        final Button shutter = a.shutter;
        shutter.performClick();
        assertFalse(shutter.isEnabled());
        camera.frame(a, sink, 9);
        Screens.settle("the interrupted upload to end", new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return shutter.isEnabled();
            }
        });
    }

    @Test
    public void surveyShutterWorksAfterAnInterruptedUpload() {
        interruptedUpload(Robolectric.buildActivity(SurveyActivity.class).setup().get());
    }

    @Test
    public void calibrationShutterWorksAfterAnInterruptedUpload() {
        interruptedUpload(Robolectric.buildActivity(CameraCalibrationActivity.class).setup().get());
    }
}
