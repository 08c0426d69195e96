package io.lumipose.app;

import static org.junit.Assert.assertEquals;
import static org.junit.Assert.assertNotNull;
import static org.junit.Assert.assertTrue;
import static org.junit.Assert.fail;
import static org.robolectric.Shadows.shadowOf;

import android.Manifest;
import android.app.Application;
import android.os.Looper;
import android.widget.TextView;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.List;
import java.util.Locale;
import java.util.regex.Matcher;
import java.util.regex.Pattern;

import org.json.JSONObject;
import org.junit.AfterClass;
import org.junit.Assume;
import org.junit.BeforeClass;
import org.junit.Test;
import org.junit.runner.RunWith;
import org.robolectric.Robolectric;
import org.robolectric.RobolectricTestRunner;
import org.robolectric.RuntimeEnvironment;
import org.robolectric.android.controller.ActivityController;
import org.robolectric.annotation.Config;
import org.robolectric.annotation.GraphicsMode;
import org.robolectric.util.ReflectionHelpers;

import io.lumipose.app.camera.FakeCamera;
import io.lumipose.app.camera.ShadowBurstSession;
import io.lumipose.app.camera.ShadowResultKeysCharacteristics;
import io.lumipose.app.camera.ShadowYuvImageReader;
import io.lumipose.client.replay.RecordedFrame;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.replay.SimulatedPhone;
import io.lumipose.client.protocol.CaptureProtocol;
import io.lumipose.client.testutil.Lumipose;
import io.lumipose.client.testutil.Repo;

/**
 * The live screen end to end, the app's own code on Android's framework classes: LiveActivity
 * fetches the map from a real {@code lumipose serve} on 127.0.0.1, opens the camera (FakeCamera:
 * the simulator's phone, its rendered frames as padded YUV images with the results the phone
 * reports), sends each pose frame through the core's pipeline and shows the answer. Without the
 * executable: fails under scripts/android_test.sh ({@code lumipose.e2e.required}), else skipped
 * with the reason.
 */
@RunWith(RobolectricTestRunner.class)
@GraphicsMode(GraphicsMode.Mode.NATIVE)
@Config(qualifiers = "w360dp-h740dp-xhdpi", shadows = {ShadowBurstSession.class, ShadowYuvImageReader.class, ShadowResultKeysCharacteristics.class})
public class LiveActivityEndToEndTest {
    /** The walk's single frames are within ~36 mm of the truth (core's ReplayEndToEndTest says why). */
    private static final double TOLERANCE_MM = 50.0;
    private static final long TIMEOUT_MS = 30_000;
    private static final Pattern POSITION = Pattern.compile("x (-?[0-9.]+)  y (-?[0-9.]+)  z (-?[0-9.]+) m");
    private static Recording walk;
    private static Lumipose.Serve serve;

    @BeforeClass
    public static void renderAndServe() throws Exception {
        if (Lumipose.executable() == null) {
            String reason = "LiveActivityEndToEndTest skipped: no lumipose executable (set -Dlumipose.exe or run "
                    + "scripts/android_test.sh)";
            if (Boolean.getBoolean("lumipose.e2e.required")) {
                fail(reason);
            }
            Assume.assumeTrue(reason, false);
        }
        Path dir = Files.createTempDirectory("lumipose-live-e2e");
        Path frames = dir.resolve("walk");
        Lumipose.simulate(walkAsTheAppCaptures(dir).toString(), frames, "--scale", "0.25", "--limit", "3");
        walk = Recording.open(frames.toFile());
        serve = Lumipose.Serve.start();
        serve.putMap(walk.map());
    }

    /**
     * The walk under one panel at the app's pose exposure (the protocol's 10 ms; the scene's 1 ms
     * would be refused as "settings in transition"), at a tenth of the scene's ISO for the same
     * exposure of the panel: the phone's lowest ISO, which the app's plan picks.
     */
    private static Path walkAsTheAppCaptures(Path dir) throws Exception {
        JSONObject scene = new JSONObject(Repo.text("simulator/scenes/walk-one-panel.json"));
        JSONObject sensor = scene.getJSONObject("sensor");
        sensor.put("exposure_s", CaptureProtocol.POSE_EXPOSURE_NS / 1e9);
        sensor.put("iso", 40);
        Path file = dir.resolve("walk-app.json");
        Files.write(file, scene.toString(2).getBytes(StandardCharsets.UTF_8));
        return file;
    }

    @AfterClass
    public static void stop() throws Exception {
        if (serve != null) {
            serve.close();
        }
    }

    @Test
    public void fetchesTheMapLocatesFramesAndShowsTheAnswer() throws Exception {
        Application app = RuntimeEnvironment.getApplication();
        shadowOf(app).grantPermissions(Manifest.permission.CAMERA);
        String mapName = walk.map().getString("name");
        new Prefs(app).edit().putString(Prefs.SERVER_URL, serve.baseUrl).putString(Prefs.API_KEY, Lumipose.Serve.KEY)
                .putString(Prefs.MAP_NAME, mapName).commit();
        SimulatedPhone phone = new SimulatedPhone(walk.frames());
        FakeCamera camera = FakeCamera.install(app, phone.facts());

        ActivityController<LiveActivity> screen = Robolectric.buildActivity(LiveActivity.class).setup();
        LiveActivity live = screen.get();
        ShadowBurstSession session;
        try {
            session = camera.awaitBurst(TIMEOUT_MS);
        } catch (AssertionError e) {
            throw new AssertionError(e.getMessage() + "; status: " + live.status.getText(), e);
        }
        assertNotNull("the map came from the server", live.map);
        assertEquals(mapName, live.map.name);
        assertEquals("one panel: pose frames only", 1, session.burst().size());
        TextView pose = ReflectionHelpers.getField(live, "pose");
        List<String> shown = new ArrayList<String>();
        for (RecordedFrame f : walk.frames()) {
            if (f.isIdFrame()) {
                continue;
            }
            String before = pose.getText().toString();
            camera.capture(session, 0, f.luma(), f.width, f.height, phone.result(f, live.plan.pose));
            String after;
            try {
                after = awaitChange(pose, before);
            } catch (AssertionError e) {
                throw new AssertionError(e.getMessage() + "; status: " + live.status.getText() + "; not sent: "
                        + live.dropCounts() + "; warnings: " + live.warnings() + "\nserver: " + serve.logTail(), e);
            }
            shown.add(after);
            Matcher m = POSITION.matcher(after);
            assertTrue(f.name + ": no position shown: " + after + "\nserver: " + serve.logTail(), m.find());
            double[] truth = f.truthPositionM();
            double dx = Double.parseDouble(m.group(1)) - truth[0];
            double dy = Double.parseDouble(m.group(2)) - truth[1];
            double dz = Double.parseDouble(m.group(3)) - truth[2];
            double errorMm = 1000 * Math.sqrt(dx * dx + dy * dy + dz * dz);
            System.out.println(String.format(Locale.US, "live e2e %s: %.1f mm from the truth", f.name, errorMm));
            assertTrue(f.name + ": " + errorMm + " mm from the truth: " + after, errorMm <= TOLERANCE_MM);
        }
        assertTrue(shown.toString(), shown.size() >= 2);
        assertTrue("the answer names the beacon: " + shown, shown.get(0).contains("beacon "));
        Screenshots.save(live, "android-live");
        screen.pause().stop().destroy();
    }

    /** Waits for the UI thread to show new text in {@code view}. */
    private static String awaitChange(TextView view, String before) throws InterruptedException {
        long end = System.currentTimeMillis() + TIMEOUT_MS;
        while (System.currentTimeMillis() < end) {
            shadowOf(Looper.getMainLooper()).idle();
            String now = view.getText().toString();
            if (!now.equals(before)) {
                return now;
            }
            Thread.sleep(10);
        }
        throw new AssertionError("nothing new shown within " + TIMEOUT_MS + " ms (still '" + before + "')");
    }
}
