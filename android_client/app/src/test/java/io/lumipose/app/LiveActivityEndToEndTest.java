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

import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.List;
import java.util.Locale;
import java.util.regex.Matcher;
import java.util.regex.Pattern;

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
import org.robolectric.util.ReflectionHelpers;

import io.lumipose.app.camera.FakeCamera;
import io.lumipose.app.camera.ShadowBurstSession;
import io.lumipose.app.camera.ShadowResultKeysCharacteristics;
import io.lumipose.app.camera.ShadowYuvImageReader;
import io.lumipose.client.replay.RecordedFrame;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.replay.SimulatedPhone;
import io.lumipose.client.testutil.Lumipose;

/**
 * The live screen end to end, the app's own code on Android's framework classes: LiveActivity
 * fetches the map from a real {@code lumipose serve} on 127.0.0.1, opens the camera (FakeCamera:
 * the simulator's phone, its rendered frames as padded YUV images with the results the phone
 * reports), sends each pose frame through the core's pipeline and shows the answer. Without the
 * executable: fails under scripts/android_test.sh ({@code lumipose.e2e.required}), else skipped
 * with the reason.
 */
@RunWith(RobolectricTestRunner.class)
@Config(shadows = {ShadowBurstSession.class, ShadowYuvImageReader.class, ShadowResultKeysCharacteristics.class})
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
        Lumipose.simulate("walk-one-panel", dir, "--scale", "0.25", "--limit", "3");
        walk = Recording.open(dir.toFile());
        serve = Lumipose.Serve.start();
        serve.putMap(walk.map());
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
        ShadowBurstSession session = camera.awaitBurst(TIMEOUT_MS);
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
            String after = awaitChange(pose, before);
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
