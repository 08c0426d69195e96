package io.lumipose.client.e2e;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
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
import io.lumipose.client.testutil.Python;

/**
 * The survey screen's session against a real {@code lumipose serve}, on the quarter-scale office set
 * of the Python survey tests (resources/survey/survey_photos.py: twelve hand-held frames of the four
 * panels from 1.2-1.6 m, each with its compass reading; the labels a person would give; the sketch
 * with every panel but the anchor a few centimetres off). Each frame goes up as a stored sample as
 * the app sends it, the labels are named on it, the survey is posted and its map made active.
 * Every surveyed panel must lie within 4 mm and 0.1 deg of the truth (the Python tests' bounds for
 * this set), the bearing within the compass's 15 deg, and the map must become the active one. A set
 * that never names panel 99 (the others still linked to the anchor) is refused, naming it.
 */
class SurveyEndToEndTest {
    private static final double TRUE_BEARING_DEG = 30.0; // simulator.survey.SurveyShots.true_bearing_deg
    private static Lumipose.Serve serve;
    private static Path photos;
    private static JSONObject set;
    private static JSONObject labels;
    private static RoomMap truth;
    private static String sketch;

    @BeforeAll
    static void start() throws Exception {
        EndToEnd.assumeExecutable();
        serve = Lumipose.Serve.start();
        photos = Files.createTempDirectory("lumipose-survey");
        Python.run("survey/survey_photos.py", photos.toString());
        set = new JSONObject(text(photos.resolve("set.json")));
        labels = new JSONObject(text(photos.resolve("labels.json")));
        truth = RoomMap.fromJson(text(photos.resolve("truth.json")));
        JSONObject sketchMap = new JSONObject(text(photos.resolve("sketch.json")));
        sketch = sketchMap.getString("name");
        serve.putMap(sketchMap);
    }

    @AfterAll
    static void stop() throws Exception {
        if (serve != null) {
            serve.close();
        }
    }

    private static String text(Path p) throws Exception {
        return new String(Files.readAllBytes(p), StandardCharsets.UTF_8);
    }

    /** The frame as the app sends it: the fixture's JSON without the simulator's truth. */
    private static FrameMeta meta(JSONObject fixture) {
        JSONObject sent = new JSONObject(fixture.toString());
        sent.remove("ground_truth");
        sent.remove("simulator");
        return FrameMeta.fromJson(sent);
    }

    private static SurveySession session(LumiposeClient client, String name, int leftOut) throws Exception {
        SurveySession s = new SurveySession(client, name);
        JSONArray frames = set.getJSONArray("frames");
        for (int i = 0; i < frames.length(); i++) {
            String frame = frames.getString(i);
            FrameMeta meta = meta(new JSONObject(text(photos.resolve(frame + ".json"))));
            int index = s.shots().size();
            s.addPhoto(Files.readAllBytes(photos.resolve(frame + ".y")), meta);
            // the user names the panels the photo shows
            JSONArray named = labels.getJSONArray(frame + ".json");
            for (int k = 0; k < named.length(); k++) {
                JSONObject l = named.getJSONObject(k);
                if (l.getInt("beacon_id") != leftOut) {
                    s.label(index, l.getInt("beacon_id"), l.getDouble("x_px"), l.getDouble("y_px"));
                }
            }
        }
        return s;
    }

    @Test
    void theSurveyPlacesEveryPanelAndTheMapBecomesActive() throws Exception {
        // the app's own settings: three attempts, the patient read timeout (stored samples and the survey go once)
        LumiposeClient client = LumiposeClient.create(new ClientConfig(serve.baseUrl, Lumipose.Serve.KEY,
                "e2e-survey", false, RetryPolicy.defaults()));
        SurveySession s = session(client, "office-surveyed", -1);
        int frames = set.getJSONArray("frames").length();
        SurveyReport r = s.survey(sketch, set.getInt("anchor"));
        assertTrue(r.framesUsed >= frames - 2, r.framesUsed + " of " + frames + " frames used");
        assertEquals(truth.beacons.size(), r.beacons.size());
        double worstMm = 0;
        double worstYawDeg = 0;
        for (SurveyReport.SurveyedBeacon b : r.beacons) {
            Beacon t = truth.beacon(b.beaconId);
            double[] c = b.centerM();
            double error = Math.sqrt(Math.pow(c[0] - t.centerM()[0], 2) + Math.pow(c[1] - t.centerM()[1], 2)
                    + Math.pow(c[2] - t.centerM()[2], 2));
            assertTrue(error < 0.004, "panel " + b.beaconId + " " + error * 1000 + " mm off");
            double yawError = ((b.yawDeg - t.yawDeg) % 360 + 540) % 360 - 180;
            assertEquals(0, yawError, 0.1, "panel " + b.beaconId + " yaw " + b.yawDeg);
            worstMm = Math.max(worstMm, error * 1000);
            worstYawDeg = Math.max(worstYawDeg, Math.abs(yawError));
        }
        System.out.printf(Locale.US, "survey e2e: %d of %d frames, worst centre %.2f mm, worst yaw %.3f deg, bearing"
                + " %.2f deg (sigma %s), rms %.3f px%n", r.framesUsed, frames, worstMm, worstYawDeg, r.bearingDeg,
                r.bearingSigmaDeg, r.rmsPx);
        double bearingError = ((r.bearingDeg - TRUE_BEARING_DEG) % 360 + 540) % 360 - 180;
        assertEquals(0, bearingError, 15.0, "the compass errs by 15 deg a reading");
        assertEquals(r.bearingDeg, r.map.bearingDeg, 0.0);
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
        SurveySession s = session(client, "office-partial", 99);
        ServerRejectedException e = assertThrows(ServerRejectedException.class,
                () -> s.survey(sketch, set.getInt("anchor")));
        assertEquals(422, e.status);
        assertTrue(e.getMessage().contains("beacon 99 "), e.getMessage());
    }
}
