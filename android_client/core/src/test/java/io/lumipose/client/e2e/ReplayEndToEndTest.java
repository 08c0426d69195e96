package io.lumipose.client.e2e;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertTrue;
import static org.junit.jupiter.api.Assertions.fail;

import java.nio.file.Files;
import java.nio.file.Path;
import java.util.List;

import org.junit.jupiter.api.AfterAll;
import org.junit.jupiter.api.Assumptions;
import org.junit.jupiter.api.BeforeAll;
import org.junit.jupiter.api.Test;

import io.lumipose.client.net.LocateResult;
import io.lumipose.client.replay.RecordedFrame;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.testutil.Lumipose;

/**
 * The app's path end to end: rendered frames played by the replay camera through the capture
 * plan, the FramePipeline (classification from results, intrinsics from results, gravity at the
 * frame's timestamp, bursts, the beacon window) and the client to a real {@code lumipose serve}.
 * The fixtures are rendered here by {@code lumipose simulate}, small, so the class takes well
 * under a minute. Without the executable: fails under scripts/android_test.sh
 * ({@code lumipose.e2e.required}), else skipped with the reason.
 */
class ReplayEndToEndTest {
    /**
     * A single frame of the walk is fixed to within about 36 mm of the camera's pose at its first
     * row at a quarter of the Mi 8's resolution (lumipose locate on the same fixtures): the 30 ms
     * rolling-shutter readout at 0.8 m/s and the hand shake move the camera while the panel's
     * rows are read. The bound leaves room above that; a wrong intrinsic or gravity is metres off.
     */
    private static final double WALK_TOLERANCE_MM = 50.0;
    /** The bound: the window must not change the answer. */
    private static final double WINDOW_TOLERANCE_MM = 0.01;
    private static Lumipose.Serve serve;
    private static Recording walk;

    @BeforeAll
    static void renderAndServe() throws Exception {
        if (Lumipose.executable() == null) {
            String reason = "ReplayEndToEndTest skipped: no lumipose executable (set -Dlumipose.exe or run "
                    + "scripts/android_test.sh)";
            if (Boolean.getBoolean("lumipose.e2e.required")) {
                fail(reason);
            }
            System.err.println(reason);
            Assumptions.abort(reason);
        }
        Path dir = Files.createTempDirectory("lumipose-replay-e2e");
        Path walkDir = dir.resolve("walk");
        Lumipose.simulate("walk-one-panel", walkDir, "--scale", "0.25", "--limit", "6");
        walk = Recording.open(walkDir.toFile());
        serve = Lumipose.Serve.start();
    }

    @AfterAll
    static void stop() throws Exception {
        if (serve != null) {
            serve.close();
        }
    }

    @Test
    void poseOnlyWalkUnderOnePanel() throws Exception {
        serve.putMap(walk.map());
        ReplayRun run = ReplayRun.play(walk, serve.baseUrl, "walk-phone", false);
        assertEquals(0, run.plan.idFramesPerBurst, "one beacon: no ID frames");
        assertTrue(run.drops.isEmpty(), "dropped: " + run.drops);
        assertTrue(run.failures.isEmpty(), "failed: " + run.failures);
        List<ReplayRun.Sent> poses = run.poses();
        assertEquals(walk.frames().size(), poses.size());
        assertEquals(poses.size(), run.poseResults.size());
        long last = -1;
        for (ReplayRun.Sent s : poses) {
            assertTrue(s.frame.timestampNs > last, "sent in capture order");
            last = s.frame.timestampNs;
            LocateResult r = s.result();
            assertTrue(r.ok, s.frame.name + ": no fix: " + r.reason + " " + r.message);
            double err = distanceMm(r.positionM(), s.frame.truthPositionM());
            System.out.printf("replay walk %s: error %.1f mm, %d of %d bytes sent%n", s.frame.name, err,
                    s.window.bodyBytes, s.frame.width * s.frame.height);
            assertTrue(err <= WALK_TOLERANCE_MM, s.frame.name + ": " + err + " mm from the truth");
            assertNotNull(s.window.frame.optJSONObject("crop"), s.frame.name + " went whole, not as a window");
        }
    }

    @Test
    void theWindowDoesNotChangeTheAnswer() throws Exception {
        serve.putMap(walk.map());
        ReplayRun run = ReplayRun.play(walk, serve.baseUrl, "window-phone", true);
        assertEquals(walk.frames().size(), run.sent.size());
        for (ReplayRun.Sent s : run.sent) {
            assertNotNull(s.whole, s.frame.name + " was not sent whole");
            LocateResult window = s.result();
            LocateResult whole = LocateResult.fromJson(s.whole.reply);
            assertTrue(window.ok && whole.ok, s.frame.name + ": " + window.reason + " / " + whole.reason);
            double difference = distanceMm(window.positionM(), whole.positionM());
            assertTrue(difference <= WINDOW_TOLERANCE_MM, s.frame.name + ": window and whole frame "
                    + difference + " mm apart");
            assertTrue(s.window.bodyBytes < s.whole.bodyBytes / 4, s.frame.name + ": the window is "
                    + s.window.bodyBytes + " of " + s.whole.bodyBytes + " bytes");
        }
    }

    static double distanceMm(double[] a, double[] b) {
        double dx = a[0] - b[0];
        double dy = a[1] - b[1];
        double dz = a[2] - b[2];
        return Math.sqrt(dx * dx + dy * dy + dz * dz) * 1000;
    }

    static RecordedFrame first(Recording r) {
        return r.frames().get(0);
    }
}
