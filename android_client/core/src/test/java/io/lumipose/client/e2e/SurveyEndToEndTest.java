package io.lumipose.client.e2e;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.File;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.util.ArrayList;
import java.util.List;
import java.util.Locale;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.AfterAll;
import org.junit.jupiter.api.BeforeAll;
import org.junit.jupiter.api.Test;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.net.ServerRejectedException;
import io.lumipose.client.survey.SurveyReport;
import io.lumipose.client.survey.SurveySession;
import io.lumipose.client.testutil.EndToEnd;
import io.lumipose.client.testutil.Lumipose;

/**
 * The survey screen's session against a real {@code lumipose serve}: six frames of the office's four
 * panels rendered from the floor ({@code lumipose simulate office --pose}, quarter resolution), each
 * stored as a sample with the compass bearing a phone would read under a map bearing of 30 deg, each
 * panel in view labelled at its true image centre; the sketch is the office map with three panels 3-5 cm
 * off. Every surveyed panel must lie within 5 mm and 0.5 deg of the truth, the map's bearing within
 * 1 deg, and the surveyed map must become the active one. A set that never names panel 200 is
 * refused, naming it.
 */
class SurveyEndToEndTest {
    private static final double BEARING_DEG = 30.0;
    private static final double[][] POSES = {
        {0.1, -0.05, 1.0, 0, 0, 0}, {-0.15, 0.1, 1.0, 8, 4, -3}, {0.2, 0.15, 0.95, -6, -5, 4},
        {-0.1, -0.2, 1.05, 15, 3, 5}, {0.05, 0.2, 1.0, -12, 6, -2}, {-0.2, 0.0, 0.9, 4, -4, -6},
    };
    private static Lumipose.Serve serve;
    private static final List<File> fixtures = new ArrayList<File>();
    private static RoomMap truth;

    @BeforeAll
    static void start() throws Exception {
        EndToEnd.assumeExecutable();
        serve = Lumipose.Serve.start();
        Path dir = Files.createTempDirectory("lumipose-survey");
        for (int i = 0; i < POSES.length; i++) {
            double[] p = POSES[i];
            Path out = dir.resolve("f" + i);
            Lumipose.simulate("office", out, "--pose", num(p[0]), num(p[1]), num(p[2]), "--ypr", num(p[3]),
                    num(p[4]), num(p[5]), "--scale", "0.25", "--seed", String.valueOf(i + 1), "--workers", "1");
            fixtures.add(out.resolve("office_0000.json").toFile());
            if (truth == null) {
                truth = RoomMap.fromJson(text(out.resolve("map.json").toFile()));
                serve.putMap(new JSONObject(text(out.resolve("map.json").toFile())));
            }
        }
        serve.putMap(sketch());
    }

    @AfterAll
    static void stop() throws Exception {
        if (serve != null) {
            serve.close();
        }
    }

    private static String num(double v) {
        return String.format(Locale.US, "%.3f", v);
    }

    private static String text(File f) throws Exception {
        return new String(Files.readAllBytes(f.toPath()), StandardCharsets.UTF_8);
    }

    /** The office map named "office-sketch" with every panel but the anchor (17) a few centimetres off. */
    private static JSONObject sketch() throws Exception {
        JSONObject m = new JSONObject(text(fixtures.get(0).toPath().resolveSibling("map.json").toFile()));
        m.put("name", "office-sketch");
        JSONArray beacons = m.getJSONArray("beacons");
        for (int i = 0; i < beacons.length(); i++) {
            JSONObject b = beacons.getJSONObject(i);
            if (b.getInt("id") != 17) {
                JSONArray c = b.getJSONArray("center_m");
                b.put("center_m", new JSONArray(new double[] {c.getDouble(0) + 0.03, c.getDouble(1) - 0.04,
                    c.getDouble(2) + 0.02}));
            }
        }
        return m;
    }

    /** The frame as the app sends it, with the compass bearing its image x would read. */
    private static FrameMeta meta(JSONObject fixture) {
        JSONArray r = fixture.getJSONObject("ground_truth").getJSONArray("rotation_wc");
        double headingDeg = Math.toDegrees(Math.atan2(r.getJSONArray(1).getDouble(0), r.getJSONArray(0).getDouble(0)));
        JSONObject sent = new JSONObject(fixture.toString());
        sent.remove("ground_truth");
        sent.remove("simulator");
        sent.put("compass_bearing_deg", BEARING_DEG - headingDeg);
        return FrameMeta.fromJson(sent);
    }

    /** Where the panel's centre lies on the frame, by the frame's true pose. */
    private static double[] project(JSONObject fixture, Beacon b) {
        JSONObject gt = fixture.getJSONObject("ground_truth");
        JSONArray r = gt.getJSONArray("rotation_wc");
        JSONArray c = gt.getJSONArray("position_m");
        double[] d = new double[3];
        double[] centre = b.centerM();
        for (int i = 0; i < 3; i++) {
            d[i] = centre[i] - c.getDouble(i);
        }
        double[] p = new double[3];
        for (int j = 0; j < 3; j++) {
            for (int i = 0; i < 3; i++) {
                p[j] += r.getJSONArray(i).getDouble(j) * d[i]; // R_wc^T (X - C)
            }
        }
        JSONObject k = fixture.getJSONObject("camera");
        return new double[] {k.getDouble("fx") * p[0] / p[2] + k.getDouble("cx"),
            k.getDouble("fy") * p[1] / p[2] + k.getDouble("cy")};
    }

    private static SurveySession session(LumiposeClient client, String name, int leftOut) throws Exception {
        SurveySession s = new SurveySession(client, name);
        for (File f : fixtures) {
            JSONObject fixture = new JSONObject(text(f));
            FrameMeta meta = meta(fixture);
            byte[] luma = Files.readAllBytes(new File(f.getParentFile(), "office_0000.y").toPath());
            int index = s.shots().size();
            s.addPhoto(luma, meta);
            for (Beacon b : truth.beacons) {
                double[] px = project(fixture, b);
                // the user names the panels the photo shows
                if (b.id != leftOut && px[0] >= 0 && px[1] >= 0 && px[0] < meta.width && px[1] < meta.height) {
                    s.label(index, b.id, px[0], px[1]);
                }
            }
        }
        return s;
    }

    @Test
    void theSurveyPlacesEveryPanelAndTheMapBecomesActive() throws Exception {
        LumiposeClient client = LumiposeClient.create(new ClientConfig(serve.baseUrl, Lumipose.Serve.KEY, "e2e-survey",
                false, new RetryPolicy(2, 200, 2.0, 1000)));
        SurveySession s = session(client, "office-surveyed", -1);
        SurveyReport r = s.survey("office-sketch", 17);
        assertEquals(POSES.length, r.framesUsed, "skipped: " + r.skipped.size());
        assertEquals(truth.beacons.size(), r.beacons.size());
        double worstMm = 0;
        double worstYawDeg = 0;
        for (SurveyReport.SurveyedBeacon b : r.beacons) {
            Beacon t = truth.beacon(b.beaconId);
            double[] c = b.centerM();
            double error = Math.sqrt(Math.pow(c[0] - t.centerM()[0], 2) + Math.pow(c[1] - t.centerM()[1], 2)
                    + Math.pow(c[2] - t.centerM()[2], 2));
            assertTrue(error < 0.005, "panel " + b.beaconId + " " + error * 1000 + " mm off");
            double yawError = ((b.yawDeg - t.yawDeg) % 360 + 540) % 360 - 180;
            assertEquals(0, yawError, 0.5, "panel " + b.beaconId + " yaw " + b.yawDeg);
            worstMm = Math.max(worstMm, error * 1000);
            worstYawDeg = Math.max(worstYawDeg, Math.abs(yawError));
        }
        System.out.printf(Locale.US, "survey e2e: %d frames, worst centre %.2f mm, worst yaw %.3f deg, bearing %.2f"
                + " deg (sigma %s), rms %.3f px%n", r.framesUsed, worstMm, worstYawDeg, r.bearingDeg,
                r.bearingSigmaDeg, r.rmsPx);
        assertEquals(BEARING_DEG, r.bearingDeg, 1.0);
        assertEquals(BEARING_DEG, r.map.bearingDeg, 1.0);
        assertTrue(r.stored);
        s.activate(r);
        assertEquals("office-surveyed", new JSONObject(client.sendJson("GET", "/v1/maps/active", null))
                .getString("name"));
        assertEquals(r.map.bearingDeg, client.fetchMap("office-surveyed").bearingDeg, 1e-9);
    }

    @Test
    void aPanelNoFrameNamesIsRefusedByName() throws Exception {
        LumiposeClient client = LumiposeClient.create(new ClientConfig(serve.baseUrl, Lumipose.Serve.KEY, "e2e-survey",
                false, new RetryPolicy(1, 0, 1.0, 0)));
        SurveySession s = session(client, "office-partial", 200);
        ServerRejectedException e = assertThrows(ServerRejectedException.class, () -> s.survey("office-sketch", 17));
        assertEquals(422, e.status);
        assertTrue(e.getMessage().contains("200"), e.getMessage());
    }
}
