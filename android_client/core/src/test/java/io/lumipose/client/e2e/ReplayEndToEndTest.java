package io.lumipose.client.e2e;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertTrue;
import static org.junit.jupiter.api.Assertions.fail;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.AfterAll;
import org.junit.jupiter.api.Assumptions;
import org.junit.jupiter.api.BeforeAll;
import org.junit.jupiter.api.Test;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.testutil.Lumipose;
import io.lumipose.client.testutil.Repo;

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
    /**
     * The office's fixes, one frame each at a quarter of the Mi 8's resolution from 1.4 m below
     * the panels, the phone held still at each capture (walking at 0.8 m/s smears a 10 ms pose
     * frame by 5 px, which the server refuses or misreads: docs/accuracy.md, "Frames as a phone
     * makes them"; this test is about the app's bursts, IDs and track); a wrong beacon is 1.2 m off.
     */
    private static final double OFFICE_TOLERANCE_MM = 60.0;
    private static Lumipose.Serve serve;
    private static Recording walk;
    private static Recording office;

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
        Path officeDir = dir.resolve("office");
        Lumipose.simulate(officeAsTheAppCaptures(dir).toString(), officeDir, "--bursts");
        office = Recording.open(officeDir.toFile());
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
        assertWindowsGiveTheWholeFramesFixes(ReplayRun.play(walk, serve.baseUrl, "window-phone", true));
    }

    @Test
    void theWindowDoesNotChangeTheAnswerInADeviceSession() throws Exception {
        serve.putMap(office.map());
        assertWindowsGiveTheWholeFramesFixes(ReplayRun.play(office, serve.baseUrl, "office-window-phone", true));
    }

    /** Every pose frame sent as a window gives the fix its whole frame gives, within 0.01 mm. */
    private static void assertWindowsGiveTheWholeFramesFixes(ReplayRun run) {
        assertTrue(run.drops.isEmpty(), "dropped: " + run.drops);
        assertFalse(run.poses().isEmpty());
        assertEquals(run.poses().size(), run.poseResults.size());
        for (ReplayRun.Sent s : run.poses()) {
            assertNotNull(s.whole, s.frame.name + " was not sent whole");
            LocateResult window = s.result();
            LocateResult whole = LocateResult.fromJson(s.whole.reply);
            assertTrue(window.ok && whole.ok, s.frame.name + ": " + window.reason + " / " + whole.reason);
            double difference = distanceMm(window.positionM(), whole.positionM());
            // A whole frame with two whole panels in view fuses their fixes (server.rooms); the
            // app's window holds one of them, so its fix is that panel's alone.
            boolean fused = whole.warnings.stream().anyMatch(w -> w.startsWith("position fused from beacons"));
            assertTrue(difference <= (fused ? OFFICE_TOLERANCE_MM : WINDOW_TOLERANCE_MM), s.frame.name
                    + ": window and whole frame " + difference + " mm apart" + (fused ? " (whole: fused)" : ""));
            assertTrue(s.window.bodyBytes < s.whole.bodyBytes / 4, s.frame.name + ": the window is "
                    + s.window.bodyBytes + " of " + s.whole.bodyBytes + " bytes");
        }
    }

    /**
     * The office scene captured as this app does, six captures along its walk's second row
     * (its first row, along the wall, sees every panel cut by the frame border):
     * <ul>
     * <li>one stream size for both kinds (the scene's ID frames are half its pose frames'), a
     *     quarter of the Mi 8's;
     * <li>the ID frames' ISO from the protocol's brightness fraction (the scene fixes 400), as the
     *     plan sets it; for that to be the scene's unsaturated 400 ISO, the pose frames are taken at
     *     ISO 30 (the panels are 8000 nits: at the pose frames' 100, a fifth of their brightness
     *     saturates the stripes 5 times over and no ID is read).
     * </ul>
     */
    private static Path officeAsTheAppCaptures(Path dir) throws Exception {
        JSONObject scene = new JSONObject(Repo.text("simulator/scenes/office.json"));
        scene.getJSONObject("camera").put("scale", 0.25);
        scene.getJSONObject("sensor").put("iso", 30);
        JSONObject id = scene.getJSONObject("id_frames");
        id.remove("scale");
        id.remove("iso");
        JSONArray poses = new JSONArray();
        for (int i = 0; i < 6; i++) {
            poses.put(new JSONObject().put("position_m", new JSONArray(new double[] {-1.0 + 0.4 * i, -1.2, 1.32}))
                    .put("ypr_deg", new JSONArray(new double[] {0, 1, -1})).put("t_s", 0.5 * i)
                    .put("velocity_mps", new JSONArray(new double[] {0, 0, 0})));
        }
        scene.put("series", new JSONObject().put("path", new JSONObject().put("kind", "poses").put("poses", poses)));
        Path file = dir.resolve("office-app.json");
        Files.write(file, scene.toString(2).getBytes(StandardCharsets.UTF_8));
        return file;
    }

    @Test
    void fourBeaconOfficeWithIdBursts() throws Exception {
        serve.putMap(office.map());
        assertOfficeBurstsRight(ReplayRun.play(office, serve.baseUrl, "office-phone", true));
    }

    /**
     * Issue 12 item 3 on a phone without per-frame control: its settings reach the sensor two
     * frames after their request, so every pose frame is tagged "id" and the frame tagged "pose"
     * has the ID exposure. Taken as their results show, the bursts and IDs are as on a phone with
     * per-frame control.
     */
    @Test
    void fourBeaconOfficeOnAPhoneWhoseSettingsLag() throws Exception {
        serve.putMap(office.map());
        ReplayRun run = ReplayRun.play(office, serve.baseUrl, "office-lagging-phone", true, 2);
        assertFalse(run.facts.hasPerFrameControl());
        assertOfficeBurstsRight(run);
    }

    private static void assertOfficeBurstsRight(ReplayRun run) {
        assertEquals(4, run.plan.idFramesPerBurst, "four beacons: ID bursts");
        assertTrue(run.drops.isEmpty(), "dropped: " + run.drops);
        assertTrue(run.failures.isEmpty(), "failed: " + run.failures);
        assertEquals(office.frames().size(), run.sent.size(), "every frame of every burst sent");
        for (FrameMeta meta : run.idResults) {
            assertEquals("id", meta.frameKind);
        }
        for (FrameMeta meta : run.poseResults) {
            assertEquals("pose", meta.frameKind, "an ID frame's answer went to the screen");
        }
        JSONObject previousTrack = null;
        long previousNs = 0;
        for (ReplayRun.Sent s : run.sent) {
            LocateResult r = s.result();
            if (s.isId()) {
                assertFalse(r.ok, s.frame.name + ": an ID frame got a fix of its own");
                assertEquals("id_frame", r.reason, s.frame.name);
                continue;
            }
            assertTrue(r.ok, s.frame.name + ": no fix: " + r.reason + " " + r.message);
            double[] truth = s.frame.truthPositionM();
            double err = distanceMm(r.positionM(), truth);
            JSONObject track = s.window.reply.optJSONObject("track");
            LocateResult whole = LocateResult.fromJson(s.whole.reply);
            System.out.printf("replay office %s: beacon %d (%s), error %.1f mm, window vs whole %s mm, track %s%n",
                    s.frame.name, r.beaconId, r.beaconIdSource, err,
                    whole.ok ? distanceMm(r.positionM(), whole.positionM()) : whole.reason, track);
            assertEquals(panelAbove(office.map(), truth), r.beaconId.intValue(), s.frame.name + ": beacon ID");
            assertTrue(err <= OFFICE_TOLERANCE_MM, s.frame.name + ": " + err + " mm from the truth");
            assertNotNull(track, s.frame.name + ": no track");
            assertFalse(track.getBoolean("outlier"), s.frame.name + ": the track took the fix for an outlier");
            if (previousTrack != null) {
                // Continuous: the filtered position moves as the phone did, not by a panel's spacing.
                double step = distanceMm(vector(track, "filtered_position_m"), vector(previousTrack,
                        "filtered_position_m"));
                double walked = 800.0 * (s.frame.timestampNs - previousNs) / 1e9;
                assertTrue(step <= walked + OFFICE_TOLERANCE_MM, s.frame.name + ": the track jumped " + step
                        + " mm while the phone walked " + walked + " mm");
            }
            previousTrack = track;
            previousNs = s.frame.timestampNs;
        }
    }

    /** The map beacon nearest the point above the camera: the panel it is under. */
    private static int panelAbove(JSONObject map, double[] camera) {
        JSONArray beacons = map.getJSONArray("beacons");
        int best = -1;
        double bestDistance = Double.POSITIVE_INFINITY;
        for (int i = 0; i < beacons.length(); i++) {
            JSONArray c = beacons.getJSONObject(i).getJSONArray("center_m");
            double d = Math.hypot(c.getDouble(0) - camera[0], c.getDouble(1) - camera[1]);
            if (d < bestDistance) {
                bestDistance = d;
                best = beacons.getJSONObject(i).getInt("id");
            }
        }
        return best;
    }

    private static double[] vector(JSONObject o, String key) {
        JSONArray a = o.getJSONArray(key);
        return new double[] {a.getDouble(0), a.getDouble(1), a.getDouble(2)};
    }

    static double distanceMm(double[] a, double[] b) {
        double dx = a[0] - b[0];
        double dy = a[1] - b[1];
        double dz = a[2] - b[2];
        return Math.sqrt(dx * dx + dy * dy + dz * dz) * 1000;
    }
}
