package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertFalse;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertNull;
import static org.junit.Assert.assertTrue;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Application;
import android.widget.Button;
import android.widget.EditText;

import java.io.File;
import java.io.FileOutputStream;
import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.util.concurrent.Callable;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.After;
import org.junit.Before;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.android.controller.ActivityController;

import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.testutil.Repo;

/**
 * Defect 2: a survey's or a calibration's photos survive the screen's recreation and the process's
 * death (a new screen without saved state), stay usable (more photos, labels, the survey or the
 * calibration), go when the user finishes or starts over; a damaged file is said and a fresh
 * session starts.
 */
@RunWith(RobolectricTestRunner.class)
public class SessionTest {
    /** Where the screens keep their session (the app's private files). */
    static final String SURVEY_FILE = "survey-session.json";
    static final String CALIBRATION_FILE = "calibration-session.json";
    private final Screens.Camera camera = new Screens.Camera();
    private FakeServer server;
    private Application app;

    @Before
    public void setUp() throws IOException {
        app = RuntimeEnvironment.getApplication();
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        server = new FakeServer().answer("POST /v1/samples", 201, ShutterTest.SAMPLE);
        Screens.server(app, server.url());
    }

    @After
    public void tearDown() {
        server.close();
    }

    private void shoot(final StillActivity a) {
        FrameSink sink = camera.start(a);
        final Button shutter = a.shutter;
        if (!"Take photo".equals(shutter.getText().toString())) {
            shutter.performClick(); // back from the held photo to the camera
        }
        shutter.performClick();
        assertFalse(shutter.isEnabled());
        camera.frame(a, sink, 5);
        Screens.settle("the photo handled", new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return shutter.isEnabled();
            }
        });
    }

    private static String photos(SurveyActivity a) {
        return Screens.text(a, "photosView");
    }

    private static void label(SurveyActivity a, int id, double x, double y) {
        Screens.<EditText>get(a, "panelField").setText(String.valueOf(id));
        a.onTap(x, y);
    }

    private static String surveyReport() throws Exception {
        JSONObject map = new JSONObject(Repo.text("shared_schemas/examples/map.json")).put("name", "surveyed");
        JSONArray beacons = new JSONArray().put(new JSONObject().put("beacon_id", 17)
                .put("center_m", new JSONArray("[1.0, 2.0, 2.7]")).put("yaw_deg", 0.5)
                .put("center_sigma_m", new JSONArray("[0.001, 0.0012, 0.002]")).put("yaw_sigma_deg", 0.05)
                .put("frames", 2));
        return new JSONObject().put("schema", "lumipose.survey-report/1").put("map", map).put("beacons", beacons)
                .put("frames_used", 2).put("rms_px", 0.4).put("skipped", new JSONArray()).put("stored", true)
                .toString();
    }

    /**
     * A recreated screen's old instance whose upload ends after the recreation (its connection
     * outlives the executor's shutdown) saves its older session: it must not write over the file
     * the new instance has changed since.
     */
    @Test
    public void theOldInstanceOfARecreatedScreenWritesNothingOverTheNewOnes() throws Exception {
        ActivityController<SurveyActivity> c = Robolectric.buildActivity(SurveyActivity.class).setup();
        SurveyActivity old = c.get();
        shoot(old);
        ScreenSession<io.lumipose.client.survey.SurveySession> oldSessions = Screens.get(old, "sessions");
        io.lumipose.client.survey.SurveySession oldSession = oldSessions.current();
        c.recreate();
        SurveyActivity now = c.get();
        shoot(now);
        label(now, 17, 10, 20);
        oldSessions.save(oldSession); // the old upload's save, late
        c.pause().stop().destroy();
        SurveyActivity restored = Robolectric.buildActivity(SurveyActivity.class).setup().get();
        assertEquals("the new instance's photo and label are kept", "photo 1: panels\nphoto 2: panels 17",
                photos(restored));
    }

    @Test
    public void surveyPhotosSurviveRecreationAndProcessDeathAndGoOn() throws Exception {
        ActivityController<SurveyActivity> c = Robolectric.buildActivity(SurveyActivity.class).setup();
        SurveyActivity a = c.get();
        shoot(a);
        label(a, 17, 10, 20);
        assertEquals("photo 1: panels 17", photos(a));

        c.recreate(); // dark mode, font size, multi-window...
        a = c.get();
        assertEquals("the session survives recreation", "photo 1: panels 17", photos(a));
        assertFalse("the surveyed map's name is the session's", Screens.<EditText>get(a, "nameField").isEnabled());
        assertTrue(Screens.text(a, "reportView"), Screens.text(a, "reportView").contains("1 photo"));
        assertEquals("back to the camera", "Take photo", a.shutter.getText().toString());
        c.pause().stop().destroy();

        ActivityController<SurveyActivity> after = Robolectric.buildActivity(SurveyActivity.class).setup();
        a = after.get(); // the process died in the background: a new screen, no saved state
        assertEquals("the session survives the process", "photo 1: panels 17", photos(a));
        shoot(a);
        assertTrue(server.requests("POST /v1/samples").get(1).uri.endsWith("%3A2"));
        label(a, 42, 30, 30);
        label(a, 17, 40, 40);
        assertEquals("photo 1: panels 17\nphoto 2: panels 42 17", photos(a));
        after.recreate();
        a = after.get();
        assertEquals("photo 1: panels 17\nphoto 2: panels 42 17", photos(a));

        server.answer("POST /v1/surveys", 200, surveyReport()).answer("PUT /v1/maps/active", 200, "{\"name\": \"surveyed\"}");
        Screens.<EditText>get(a, "anchorField").setText("17");
        camera.start(a);
        button(a, "Survey").performClick();
        final SurveyActivity done = a;
        Screens.settle("the survey", new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return Screens.text(done, "reportView").contains("is now the active map");
            }
        });
        JSONObject request = new JSONObject(server.requests("POST /v1/surveys").get(0).text());
        assertEquals(2, request.getJSONArray("samples").length());
        assertEquals(2, request.getJSONArray("samples").getJSONObject(1).getJSONArray("labels").length());
        assertFalse("a finished survey's file is dropped", new File(a.getFilesDir(), SURVEY_FILE)
                .exists());
        after.pause().stop().destroy();
        SurveyActivity fresh = Robolectric.buildActivity(SurveyActivity.class).setup().get();
        assertEquals("", photos(fresh));
    }

    private static Button button(android.app.Activity a, String text) {
        return Screens.button(a, text);
    }

    @Test
    public void startOverDropsTheSurvey() {
        ActivityController<SurveyActivity> c = Robolectric.buildActivity(SurveyActivity.class).setup();
        SurveyActivity a = c.get();
        shoot(a);
        assertEquals("photo 1: panels", photos(a));
        button(a, "Start over").performClick();
        assertEquals("", photos(a));
        assertTrue(Screens.<EditText>get(a, "nameField").isEnabled());
        assertFalse(new File(a.getFilesDir(), SURVEY_FILE).exists());
        c.recreate();
        assertEquals("", photos(c.get()));
        shoot(c.get());
        assertTrue("a new session numbers from 1 again",
                server.requests("POST /v1/samples").get(1).uri.endsWith("%3A1"));
    }

    private static void damage(File f) throws IOException {
        f.getParentFile().mkdirs();
        FileOutputStream out = new FileOutputStream(f);
        out.write("{\"schema\": \"lumipose.survey-session/1\", \"name\": \"x\", \"sho".getBytes(StandardCharsets.UTF_8));
        out.close();
    }

    @Test
    public void aDamagedSurveyFileIsSaidAndAFreshSessionStarts() throws IOException {
        damage(new File(app.getFilesDir(), SURVEY_FILE));
        SurveyActivity a = Robolectric.buildActivity(SurveyActivity.class).setup().get();
        assertTrue(Screens.text(a, "reportView"), Screens.text(a, "reportView").contains("could not be restored"));
        assertNull(session(a));
        shoot(a);
        assertEquals("photo 1: panels", photos(a));
    }

    @Test
    public void aDamagedCalibrationFileIsSaidAndAFreshSessionStarts() throws IOException {
        damage(new File(app.getFilesDir(), CALIBRATION_FILE));
        CameraCalibrationActivity a = Robolectric.buildActivity(CameraCalibrationActivity.class).setup().get();
        assertTrue(Screens.text(a, "report"), Screens.text(a, "report").contains("could not be restored"));
        assertNull(session(a));
    }

    private static String okReport(int w, int h) throws Exception {
        DeviceProfile p = new DeviceProfile("phone-calibrated", "phone", "unknown", "rear", 3.2e-6, 1.92e-4, w, h,
                new double[] {0.01, 0, 0, 0, 0}, 0.1, new DeviceProfile.MeasuredPinhole(61, 60.5, 32, 23, 0.21, 2));
        return new JSONObject().put("schema", "lumipose.calibration/1").put("ok", true).put("profile", p.toJson())
                .put("rms_px", 0.21).put("coverage", 0.5).put("coverage_cells", new JSONArray("[[1, 0, 2], [0, 1, 0]]"))
                .put("max_tilt_deg", 41.0).put("advice", new JSONArray()).put("views", new JSONArray()).toString();
    }

    @Test
    public void calibrationPhotosSurviveRecreationAndProcessDeathAndCalibrate() throws Exception {
        ActivityController<CameraCalibrationActivity> c = Robolectric.buildActivity(CameraCalibrationActivity.class)
                .setup();
        CameraCalibrationActivity a = c.get();
        io.lumipose.client.capture.CapturePlan plan = a.plan(camera.facts, camera.positioning);
        server.answer("POST /v1/calibrations/views", 200, ShutterTest.boardView(plan));
        shoot(a);
        assertTrue(Screens.text(a, "counts"), Screens.text(a, "counts").startsWith("1 photos, 1 with the board"));

        c.recreate();
        a = c.get();
        assertTrue("the session survives recreation: " + Screens.text(a, "counts"),
                Screens.text(a, "counts").startsWith("1 photos, 1 with the board"));
        assertTrue(Screens.<Button>get(a, "calibrate").isEnabled());
        assertFalse(Screens.<EditText>get(a, "boardField").isEnabled());
        c.pause().stop().destroy();

        ActivityController<CameraCalibrationActivity> after = Robolectric.buildActivity(
                CameraCalibrationActivity.class).setup();
        a = after.get();
        assertTrue("the session survives the process: " + Screens.text(a, "counts"),
                Screens.text(a, "counts").startsWith("1 photos, 1 with the board"));
        shoot(a);
        assertTrue(server.requests("POST /v1/calibrations/views").get(1).uri.endsWith("photo-2"));
        assertTrue(Screens.text(a, "counts"), Screens.text(a, "counts").startsWith("2 photos, 2 with the board"));

        server.answer("POST /v1/calibrations", 200, okReport(plan.output.width, plan.output.height))
                .answer("PUT /v1/profiles/", 200, "{}");
        Screens.<Button>get(a, "calibrate").performClick();
        final CameraCalibrationActivity done = a;
        Screens.settle("the calibration", new Callable<Boolean>() {
            @Override
            public Boolean call() {
                return Screens.text(done, "report").startsWith("Calibrated");
            }
        });
        assertEquals("the restored view and the new one", 2,
                new JSONObject(lastCalibration()).getJSONArray("views").length());
        assertNotNull(new Prefs(a).calibratedProfile(camera.facts.cameraId));
        assertFalse("a kept profile's session file is dropped",
                new File(a.getFilesDir(), CALIBRATION_FILE).exists());
    }

    private String lastCalibration() {
        for (FakeServer.Request r : server.requests("POST /v1/calibrations")) {
            if (r.uri.equals("/v1/calibrations")) {
                return r.text();
            }
        }
        throw new AssertionError("no calibration posted");
    }

    @Test
    public void startOverDropsTheCalibration() {
        ActivityController<CameraCalibrationActivity> c = Robolectric.buildActivity(CameraCalibrationActivity.class)
                .setup();
        CameraCalibrationActivity a = c.get();
        try {
            server.answer("POST /v1/calibrations/views", 200, ShutterTest.boardView(a.plan(camera.facts,
                    camera.positioning)));
        } catch (Exception e) {
            throw new AssertionError(e);
        }
        shoot(a);
        button(a, "Start over").performClick();
        assertEquals("No photo yet.", Screens.text(a, "counts"));
        assertFalse(Screens.<Button>get(a, "calibrate").isEnabled());
        assertTrue(Screens.<EditText>get(a, "boardField").isEnabled());
        assertFalse(new File(a.getFilesDir(), CALIBRATION_FILE).exists());
        c.recreate();
        assertNull("nothing restored", session(c.get()));
        assertTrue(Screens.<EditText>get(c.get(), "boardField").isEnabled());
    }

    /** The screen's session (null: none). */
    private static Object session(Object screen) {
        ScreenSession<?> sessions = Screens.get(screen, "sessions");
        return sessions.current();
    }
}
