package io.lumipose.client.survey;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.charset.StandardCharsets;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.FakeTransport;
import io.lumipose.client.net.HttpCall;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.net.ServerRejectedException;
import io.lumipose.client.testutil.Repo;

/** The survey screen's flow against scripted server answers: samples, labels, the request, the active map. */
class SurveySessionTest {
    private static final int W = 80;
    private static final int H = 60;
    private static final String NO_FIX = "{\"schema\": \"lumipose.result/1\", \"ok\": false, \"reason\": "
            + "\"beacon_id_unknown\"}";

    private final FakeTransport transport = new FakeTransport();
    private final SurveySession session = new SurveySession(new LumiposeClient(new ClientConfig("http://server:8000",
            "key", "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), transport, ms -> { }), "office-surveyed");

    private static FrameMeta photo() {
        return FrameMeta.builder(W, H).camera(new Intrinsics(70, 70, 39.5, 29.5, null, null, null, null))
                .gravityCamera(new double[] {0, 0, -1}).compassBearingDeg(33.0).frameKind("pose").build();
    }

    private static String sample(String id) {
        return "{\"id\": \"" + id + "\", \"label\": \"survey\", \"result\": " + NO_FIX + "}";
    }

    private static String report(boolean stored) throws Exception {
        JSONObject map = new JSONObject(Repo.text("shared_schemas/examples/map.json")).put("name", "office-surveyed")
                .put("bearing_deg", 21.5);
        JSONArray beacons = new JSONArray();
        for (int id : new int[] {17, 42}) {
            beacons.put(new JSONObject().put("beacon_id", id).put("center_m", new JSONArray("[1.0, 2.0, 2.7]"))
                    .put("yaw_deg", 0.5).put("center_sigma_m", new JSONArray("[0.001, 0.0012, 0.002]"))
                    .put("yaw_sigma_deg", 0.05).put("frames", 12));
        }
        return new JSONObject().put("schema", "lumipose.survey-report/1").put("map", map).put("beacons", beacons)
                .put("frames_used", 2).put("rms_px", 0.4).put("bearing_deg", 21.5).put("bearing_sigma_deg", 3.1)
                .put("skipped", new JSONArray().put(new JSONObject().put("name", "s3").put("why", "one panel named")))
                .put("stored", stored).toString();
    }

    private static JSONObject body(HttpCall c) {
        return new JSONObject(new String(c.body(), StandardCharsets.UTF_8));
    }

    @Test
    void photosAreStoredLabelledSurveyedAndTheMapBecomesActive() throws Exception {
        transport.reply(201, sample("s1")).reply(201, sample("s2")).reply(200, report(true))
                .reply(200, "{\"name\": \"office-surveyed\"}");
        byte[] luma = new byte[W * H];
        luma[3] = 7;
        SurveySession.Shot first = session.addPhoto(luma, photo());
        session.addPhoto(luma, photo());
        assertEquals("s1", first.sampleId);
        assertFalse(first.stored.ok, "the sketch may not locate it: the survey does");
        HttpCall store = transport.calls.get(0);
        assertEquals("http://server:8000/v1/samples?label=survey%3Aoffice-surveyed%3A1", store.url);
        FrameMeta sent = FrameMeta.fromJson(store.headers.get("X-Lumipose-Frame"));
        assertEquals(33.0, sent.compassBearingDeg, 0.0, "the compass reading goes with every photo");
        assertEquals(W, sent.width, "whole");
        session.label(0, 17, 10.5, 20);
        session.label(0, 42, 70, 20);
        session.label(1, 42, 40, 30);

        SurveyReport r = session.survey("office", 17);
        JSONObject request = body(transport.calls.get(2));
        assertEquals("http://server:8000/v1/surveys", transport.calls.get(2).url);
        assertEquals("office-surveyed", request.getString("name"));
        assertEquals("office", request.getString("sketch"));
        assertEquals(17, request.getInt("anchor"));
        assertTrue(request.getBoolean("store"));
        JSONArray samples = request.getJSONArray("samples");
        assertEquals(2, samples.length());
        assertEquals("s1", samples.getJSONObject(0).getString("sample_id"));
        assertTrue(new JSONObject("{\"beacon_id\": 17, \"x_px\": 10.5, \"y_px\": 20}")
                .similar(samples.getJSONObject(0).getJSONArray("labels").getJSONObject(0)));
        assertEquals(1, samples.getJSONObject(1).getJSONArray("labels").length());

        assertEquals(2, r.beacons.size());
        assertEquals(0.0012, r.beacons.get(0).centerSigmaM()[1], 0.0);
        assertEquals("one panel named", r.skipped.get(0).why);
        assertEquals(21.5, r.map.bearingDeg, 0.0);
        assertEquals(3.1, r.bearingSigmaDeg, 0.0);
        session.activate(r);
        HttpCall active = transport.calls.get(3);
        assertEquals("PUT", active.method);
        assertEquals("http://server:8000/v1/maps/active", active.url);
        assertEquals("office-surveyed", body(active).getString("name"));
        assertEquals("key", active.headers.get("X-API-Key"));
    }

    /**
     * With the app's own settings (three attempts, the patient read timeout): a photo stored and a
     * survey computed slower than that timeout are awaited, each POST sent once, and the map activated.
     */
    @Test
    void slowAnswersAreAwaitedAndNothingIsSentTwice() throws Exception {
        FakeTransport slow = new FakeTransport();
        LumiposeClient app = new LumiposeClient(new ClientConfig("http://server:8000", "key", "phone-1", false,
                RetryPolicy.defaults()), slow, ms -> { });
        SurveySession s = new SurveySession(app, "office-surveyed");
        int late = ClientConfig.PATIENT_READ_TIMEOUT_MS + 5000;
        slow.replyAfter(late, 201, sample("s1")).replyAfter(120000, 200, report(true))
                .reply(200, "{\"name\": \"office-surveyed\"}");
        s.addPhoto(new byte[W * H], photo());
        s.label(0, 17, 10, 20);
        SurveyReport r = s.survey("office", 17);
        assertEquals(2, slow.calls.size(), "one POST of the photo, one of the survey");
        assertEquals("http://server:8000/v1/surveys", slow.calls.get(1).url);
        assertTrue(r.stored);
        s.activate(r);
        assertEquals(3, slow.calls.size());
    }

    /** No answer at all: one POST, and the error says the map may be stored, not that the survey was refused. */
    @Test
    void aLostSurveyAnswerIsNotSentAgain() throws Exception {
        FakeTransport lost = new FakeTransport();
        LumiposeClient app = new LumiposeClient(new ClientConfig("http://server:8000", "key", "phone-1", false,
                RetryPolicy.defaults()), lost, ms -> { });
        SurveySession s = new SurveySession(app, "office-surveyed");
        lost.reply(201, sample("s1")).fail("connection reset").reply(200, report(true));
        s.addPhoto(new byte[W * H], photo());
        java.io.IOException e = assertThrows(java.io.IOException.class, () -> s.survey("office", 17));
        assertEquals(2, lost.calls.size(), "the survey was posted once");
        assertTrue(e.getMessage().contains("sent once"), e.getMessage());
    }

    @Test
    void anUnconnectedPanelIsTheServersRefusalNamingIt() throws Exception {
        transport.reply(201, sample("s1")).reply(422, "{\"error\": \"survey_refused\", \"field\": \"samples\", "
                + "\"message\": \"panel 42 is not connected to the anchor 17 by any frame\"}");
        session.addPhoto(new byte[W * H], photo());
        ServerRejectedException e = assertThrows(ServerRejectedException.class, () -> session.survey("office", 17));
        assertEquals(422, e.status);
        assertTrue(e.getMessage().contains("panel 42 is not connected"), e.getMessage());
    }

    @Test
    void badInputIsRefusedNamingWhatIsWrong() throws Exception {
        assertEquals("name", assertThrows(ContractException.class, () -> new SurveySession(null, "my map")).field);
        assertThrows(IllegalStateException.class, () -> session.survey("office", 17));
        assertThrows(IllegalArgumentException.class, () -> session.label(0, 17, 1, 1));
        assertThrows(IllegalArgumentException.class,
                () -> session.addPhoto(new byte[100], photo().window(0, 0, 10, 10, null)));
        transport.reply(201, sample("s1")).reply(200, report(false));
        session.addPhoto(new byte[W * H], photo());
        assertTrue(assertThrows(IllegalArgumentException.class, () -> session.label(0, 17, 80, 1)).getMessage()
                .contains("outside the 80x60 photo"));
        assertThrows(IllegalArgumentException.class, () -> session.label(0, 256, 1, 1));
        assertThrows(IllegalArgumentException.class, () -> session.survey("office", -1));
        assertEquals("sketch", assertThrows(ContractException.class, () -> session.survey("", 17)).field);
        SurveyReport notStored = session.survey("office", 17);
        assertThrows(IllegalStateException.class, () -> session.activate(notStored));
        assertEquals(2, transport.calls.size(), "no PUT for a map that was not stored");
    }

    /** What the screen keeps of a session (its file in the app's storage): read back equal, and usable. */
    @Test
    void aSessionSurvivesItsJsonAndGoesOn() throws Exception {
        transport.reply(201, sample("s1")).reply(201, sample("s2"));
        session.addPhoto(new byte[W * H], photo());
        session.addPhoto(new byte[W * H], photo());
        session.label(0, 17, 10.5, 20);
        session.label(0, 42, 70, 20);
        session.label(1, 42, 40.25, 30);
        JSONObject saved = session.toJson();
        assertEquals(SurveySession.SCHEMA, saved.getString("schema"));

        FakeTransport later = new FakeTransport();
        SurveySession back = SurveySession.fromJson(new LumiposeClient(new ClientConfig("http://server:8000", "key",
                "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), later, ms -> { }), saved.toString());
        assertTrue(saved.similar(back.toJson()), back.toJson().toString());
        assertEquals("office-surveyed", back.name());
        assertEquals(2, back.shots().size());
        SurveySession.Shot first = back.shots().get(0);
        assertEquals("s1", first.sampleId);
        assertEquals(W, first.width);
        assertEquals(H, first.height);
        assertFalse(first.stored.ok);
        assertEquals("beacon_id_unknown", first.stored.reason);
        assertEquals(2, first.labels.size());
        assertEquals(42, first.labels.get(1).beaconId);
        assertEquals(40.25, back.shots().get(1).labels.get(0).xPx, 0.0);

        // more photos (numbered on), labels on old and new ones, the survey of them all
        later.reply(201, sample("s3")).reply(200, report(true));
        back.addPhoto(new byte[W * H], photo());
        assertEquals("http://server:8000/v1/samples?label=survey%3Aoffice-surveyed%3A3", later.calls.get(0).url);
        back.label(2, 17, 5, 5);
        back.label(1, 17, 6, 6);
        back.survey("office", 17);
        JSONArray samples = body(later.calls.get(1)).getJSONArray("samples");
        assertEquals(3, samples.length());
        assertEquals("s2", samples.getJSONObject(1).getString("sample_id"));
        assertEquals(2, samples.getJSONObject(1).getJSONArray("labels").length());
        assertEquals(1, samples.getJSONObject(2).getJSONArray("labels").length());
    }

    @Test
    void anEmptySessionSurvivesItsJson() {
        SurveySession back = SurveySession.fromJson(null, session.toJson().toString());
        assertEquals(0, back.shots().size());
        assertTrue(session.toJson().similar(back.toJson()));
    }

    /** A damaged or foreign file is refused naming what is wrong, never half read. */
    @Test
    void aDamagedSessionIsRefusedNamingWhatIsWrong() throws Exception {
        transport.reply(201, sample("s1"));
        session.addPhoto(new byte[W * H], photo());
        session.label(0, 17, 10.5, 20);
        String good = session.toJson().toString();

        ContractException cut = assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, good.substring(0, good.length() / 2)));
        assertEquals("survey session", cut.field);
        assertTrue(cut.getMessage().contains("not a JSON object"), cut.getMessage());
        assertThrows(ContractException.class, () -> SurveySession.fromJson(null, ""));
        assertEquals("schema", assertThrows(ContractException.class, () -> SurveySession.fromJson(null,
                new JSONObject(good).put("schema", "lumipose.calibration-session/1").toString())).field);
        assertEquals("schema", assertThrows(ContractException.class, () -> SurveySession.fromJson(null,
                "{\"name\": \"x\", \"photos\": 0}")).field);
        assertEquals("name", assertThrows(ContractException.class, () -> SurveySession.fromJson(null,
                new JSONObject(good).put("name", "no spaces allowed?").toString())).field);

        JSONObject lostSample = new JSONObject(good);
        lostSample.getJSONArray("shots").getJSONObject(0).remove("sample_id");
        assertEquals("shots[0].sample_id", assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, lostSample.toString())).field);
        JSONObject badResult = new JSONObject(good);
        badResult.getJSONArray("shots").getJSONObject(0).getJSONObject("stored").remove("ok");
        assertEquals("shots[0].stored.ok", assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, badResult.toString())).field);
        JSONObject outside = new JSONObject(good);
        outside.getJSONArray("shots").getJSONObject(0).getJSONArray("labels").getJSONObject(0).put("x_px", W + 5);
        ContractException e = assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, outside.toString()));
        assertEquals("shots[0].labels[0]", e.field);
        assertTrue(e.getMessage().contains("outside"), e.getMessage());
        JSONObject badId = new JSONObject(good);
        badId.getJSONArray("shots").getJSONObject(0).getJSONArray("labels").getJSONObject(0).put("beacon_id", "17");
        assertEquals("shots[0].labels[0].beacon_id", assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, badId.toString())).field);
        assertEquals("photos", assertThrows(ContractException.class,
                () -> SurveySession.fromJson(null, new JSONObject(good).put("photos", 0).toString())).field);
    }
}
