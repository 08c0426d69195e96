package io.lumipose.client.calibration;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.charset.StandardCharsets;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.FakeTransport;
import io.lumipose.client.net.HttpCall;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.net.ServerRejectedException;
import io.lumipose.client.sensor.LensFacing;

/** The calibration screen's flow against scripted server answers: what goes up, what is kept, what is stored. */
class CalibrationSessionTest {
    private static final int W = 64;
    private static final int H = 48;
    private static final BoardSpec BOARD = new BoardSpec(7, 5, 0.03, 0.022, null);
    private static final Intrinsics CAMERA = new Intrinsics(60, 60, 31.5, 23.5, null, 3.2e-6, 1.92e-4, "phone");

    private final FakeTransport transport = new FakeTransport();
    private final CalibrationSession session = new CalibrationSession(new LumiposeClient(new ClientConfig(
            "http://server:8000", "key", "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), transport,
            ms -> { }), BOARD);

    private static FrameMeta photo() {
        return FrameMeta.builder(W, H).camera(CAMERA).exposureS(0.02).iso(800.0).frameKind("pose").build();
    }

    private static String view(String name, double[]... corners) {
        JSONArray ids = new JSONArray();
        JSONArray points = new JSONArray();
        for (int i = 0; i < corners.length; i++) {
            ids.put(i + 3);
            points.put(new JSONArray(corners[i]));
        }
        return new JSONObject().put("name", name).put("width", W).put("height", H).put("corner_ids", ids)
                .put("corners_px", points).toString();
    }

    private static String error(String code, String message) {
        return new JSONObject().put("error", code).put("field", JSONObject.NULL).put("message", message).toString();
    }

    private static JSONObject body(HttpCall c) {
        return new JSONObject(new String(c.body(), StandardCharsets.UTF_8));
    }

    private static String okReport(DeviceProfile profile) {
        return new JSONObject().put("schema", "lumipose.calibration/1").put("ok", true).put("profile", profile.toJson())
                .put("rms_px", 0.21).put("coverage", 0.5).put("coverage_cells", new JSONArray("[[1, 0, 2], [0, 1, 0]]"))
                .put("max_tilt_deg", 41.0).put("advice", new JSONArray())
                .put("views", new JSONArray().put(new JSONObject().put("name", "photo-1").put("corners", 2)
                        .put("note", "blurred"))).toString();
    }

    private static DeviceProfile calibrated() {
        return new DeviceProfile("phone-calibrated", "phone", "unknown", "rear", 3.2e-6, 1.92e-4, W, H,
                new double[] {0.01, 0, 0, 0, 0}, 0.1, new DeviceProfile.MeasuredPinhole(61, 60.5, 32, 23, 0.21, 2));
    }

    @Test
    void photosGoUpOnceAndTheViewsAndCoverageAreKept() throws Exception {
        transport.reply(200, view("photo-1", new double[] {5, 5}, new double[] {60, 40}))
                .reply(422, error("no_board", "no ChArUco corners found on the photo"))
                .reply(200, view("photo-3", new double[] {33, 5}));
        byte[] luma = new byte[W * H];
        luma[7] = 9;
        CalibrationSession.Photo first = session.addPhoto(luma, photo());
        assertTrue(first.found());
        assertEquals(2, first.view.corners());
        CalibrationSession.Photo blank = session.addPhoto(luma, photo());
        assertFalse(blank.found());
        assertTrue(blank.refusal.contains("no ChArUco corners found"), blank.refusal);
        session.addPhoto(luma, photo());

        HttpCall call = transport.calls.get(0);
        assertEquals("http://server:8000/v1/calibrations/views?name=photo-1", call.url);
        assertEquals("POST", call.method);
        assertEquals(BOARD.toJson().toString(), new JSONObject(call.headers.get("X-Lumipose-Board")).toString());
        FrameMeta sent = FrameMeta.fromJson(call.headers.get("X-Lumipose-Frame"));
        assertEquals(W, sent.width);
        assertNull(sent.crop, "a board photo goes whole");
        assertArrayEquals(luma, call.body());
        assertEquals("http://server:8000/v1/calibrations/views?name=photo-2", transport.calls.get(1).url);

        assertEquals(3, session.photos());
        assertEquals(2, session.views().size());
        BoardCoverage c = session.coverage();
        assertEquals(4, c.rows, "the default grid of a landscape image: 6 x 4");
        assertEquals(6, c.columns);
        assertEquals(1, c.count(0, 0));
        assertEquals(1, c.count(0, 3), "photo-3's corner");
        assertEquals(0.0, c.coverage(), 0.0, "no cell with 3 corners");
    }

    @Test
    void theViewsGoToTheCalibrationAndAnAcceptedProfileIsStored() throws Exception {
        transport.reply(200, view("photo-1", new double[] {5, 5}, new double[] {60, 40}))
                .reply(200, okReport(calibrated())).reply(200, calibrated().toJson().toString());
        session.addPhoto(new byte[W * H], photo());
        DeviceProfile phone = DeviceProfile.ofPhone("phone", "phone", LensFacing.BACK, CAMERA, W, H);
        CalibrationSession.Outcome o = session.calibrate(phone, null);

        JSONObject request = body(transport.calls.get(1));
        assertEquals("http://server:8000/v1/calibrations", transport.calls.get(1).url);
        assertEquals(BOARD.toJson().toString(), request.getJSONObject("board").toString());
        assertEquals(1, request.getJSONArray("views").length());
        assertEquals(new JSONObject(view("photo-1", new double[] {5, 5}, new double[] {60, 40})).toString(),
                request.getJSONArray("views").getJSONObject(0).toString(), "the view as the server gave it");
        assertTrue(phone.toJson().similar(request.getJSONObject("device")), request.toString());
        assertFalse(request.has("profile_id"), "the server names it <device id>-calibrated");

        assertTrue(o.report.ok);
        assertTrue(o.stored);
        assertEquals(0.21, o.report.rmsPx, 0.0);
        assertEquals("[photo-1: blurred]", o.report.leftOut.toString());
        HttpCall put = transport.calls.get(2);
        assertEquals("PUT", put.method);
        assertEquals("http://server:8000/v1/profiles/phone-calibrated", put.url);
        assertEquals("key", put.headers.get("X-API-Key"));
        assertTrue(calibrated().toJson().similar(body(put)), body(put).toString());
        assertEquals(61.0, o.report.profile.intrinsics.fx, 0.0);
        BoardCoverage c = session.coverage();
        assertEquals(2, c.rows, "the report's grid from now on");
        assertEquals(3, c.columns);
    }

    @Test
    void aRefusedSetGivesItsAdviceAndStoresNothing() throws Exception {
        String refused = new JSONObject().put("ok", false).put("coverage", 0.1).put("message", "too few views")
                .put("advice", new JSONArray().put("cover the corners").put("tilt the board more")).toString();
        transport.reply(200, view("photo-1", new double[] {5, 5})).reply(200, refused);
        session.addPhoto(new byte[W * H], photo());
        CalibrationSession.Outcome o = session.calibrate("xiaomi-mi8-rear", "mine");
        assertFalse(o.report.ok);
        assertFalse(o.stored);
        assertEquals("[cover the corners, tilt the board more]", o.report.advice.toString());
        assertEquals("too few views", o.report.message);
        JSONObject request = body(transport.calls.get(1));
        assertEquals("xiaomi-mi8-rear", request.getString("device"));
        assertEquals("mine", request.getString("profile_id"));
        assertEquals(2, transport.calls.size(), "nothing stored");
    }

    /**
     * Issue 29: a board the user owns (OpenCV's chessboard, printed inverted) goes up as the contract
     * says; the server's word on how it found the board (inverted, a mirrored front-camera photo) is
     * kept and sent back, so its report can say it; a refused set's fit is read, marked not trusted.
     */
    @Test
    void aBoardTheUserOwnsAndHowItWasFoundGoBackToTheServer() throws Exception {
        BoardSpec chessboard = BoardSpec.chessboard(10, 7, 0.025, true);
        FakeTransport t = new FakeTransport();
        CalibrationSession s = new CalibrationSession(new LumiposeClient(new ClientConfig("http://server:8000", "key",
                "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), t, ms -> { }), chessboard);
        String found = new JSONObject(view("photo-1", new double[] {5, 5}, new double[] {60, 40}))
                .put("inverted", true).put("mirrored", true).toString();
        JSONObject fitted = new JSONObject().put("trusted", false).put("width", W).put("height", H).put("fx", 59.2)
                .put("fy", 59.0).put("cx", 30.1).put("cy", 24.2)
                .put("distortion", new JSONArray("[-0.2, 0.1, 0, 0, 0]"));
        String refused = new JSONObject().put("ok", false).put("coverage", 0.1).put("fitted", fitted)
                .put("message", "coverage 10 %; photos were mirrored: un-mirrored before fitting (1 of 1)")
                .put("advice", new JSONArray().put("cover the corners")).toString();
        t.reply(200, found).reply(200, refused);
        CalibrationSession.Photo photo = s.addPhoto(new byte[W * H], photo());
        assertTrue(photo.view.inverted && photo.view.mirrored);
        assertEquals(" (board found inverted, photo mirrored: un-mirrored)", photo.view.foundAs(), "the photo's line");
        String header = t.calls.get(0).headers.get("X-Lumipose-Board");
        assertTrue(new JSONObject("{\"schema\": \"lumipose.board/1\", \"kind\": \"chessboard\", \"squares_x\": 10, "
                + "\"squares_y\": 7, \"square_m\": 0.025, \"inverted\": true}") // a chessboard's has no dictionary
                .similar(new JSONObject(header)), header);

        // the session's file keeps them (the screen's restore after process death)
        CalibrationSession back = CalibrationSession.fromJson(new LumiposeClient(new ClientConfig(
                "http://server:8000", "key", "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), t, ms -> { }),
                s.toJson().toString());
        assertTrue(back.board().isChessboard() && back.board().inverted);
        assertTrue(back.views().get(0).mirrored && back.views().get(0).inverted);

        CalibrationSession.Outcome o = back.calibrate("xiaomi-mi8-rear", null);
        JSONObject request = body(t.calls.get(1));
        assertTrue(new JSONObject(found).similar(request.getJSONArray("views").getJSONObject(0)),
                "the view as the server gave it: " + request.getJSONArray("views"));
        assertEquals(chessboard.toJson().toString(), request.getJSONObject("board").toString());
        assertFalse(o.report.ok);
        assertFalse(o.report.fitted.trusted);
        assertEquals(59.2, o.report.fitted.fx, 0.0);
        assertEquals(24.2, o.report.fitted.cy, 0.0);
        assertEquals(-0.2, o.report.fitted.distortion()[0], 0.0);
        assertNull(o.report.profile, "a refused set's fit is no profile");
        String shown = o.describe();
        assertTrue(shown.contains("\nFitted, NOT TRUSTED (not used): fx 59.2  fy 59.0  cx 30.1  cy 24.2 px at 64x48, "
                + "k1 -0.200"), shown);
        assertTrue(shown.startsWith("Not calibrated: coverage 10 %; photos were mirrored"), shown);
        assertEquals(2, t.calls.size(), "nothing stored");
    }

    @Test
    void aReportsFitIsCheckedAsTheContractSaysIt() {
        String fit = "\"fitted\": {\"trusted\": %s, \"width\": 64, \"height\": 48, \"fx\": 60, \"fy\": 60, "
                + "\"cx\": 32, \"cy\": 24, \"distortion\": %s}";
        String report = "{\"ok\": false, \"coverage\": 0.2, " + fit + "}";
        assertFalse(CalibrationReport.fromJson(String.format(report, "false", "[0, 0, 0, 0, 0]")).fitted.trusted);
        assertNull(CalibrationReport.fromJson("{\"ok\": false, \"coverage\": 0.2, \"fitted\": null}").fitted,
                "null when nothing could be fitted");
        assertEquals("fitted.distortion", assertThrows(ContractException.class,
                () -> CalibrationReport.fromJson(String.format(report, "false", "[0, 0, 0]"))).field);
        assertEquals("fitted.trusted", assertThrows(ContractException.class,
                () -> CalibrationReport.fromJson(String.format(report, "true", "[0, 0, 0, 0, 0]"))).field,
                "a refused set's fit is not trusted");
    }

    @Test
    void aProfileTheServerWouldNotStoreIsStillReported() throws Exception {
        transport.reply(200, view("photo-1", new double[] {5, 5})).reply(200, okReport(calibrated()))
                .reply(401, error("unauthorized", "missing or wrong API key"));
        session.addPhoto(new byte[W * H], photo());
        CalibrationSession.Outcome o = session.calibrate("xiaomi-mi8-rear", null);
        assertTrue(o.report.ok);
        assertFalse(o.stored);
        assertTrue(o.storeError.contains("API key"), o.storeError);
    }

    @Test
    void badInputIsRefusedNamingWhatIsWrong() throws Exception {
        assertEquals("no board photo yet: shoot the board first", assertThrows(IllegalStateException.class,
                () -> session.calibrate("xiaomi-mi8-rear", null)).getMessage());
        FrameMeta window = photo().window(0, 0, 10, 10, null);
        assertThrows(IllegalArgumentException.class, () -> session.addPhoto(new byte[100], window));
        transport.reply(200, view("photo-1", new double[] {5, 5}));
        session.addPhoto(new byte[W * H], photo());
        FrameMeta bigger = FrameMeta.builder(2 * W, 2 * H).camera(CAMERA).build();
        IllegalArgumentException e = assertThrows(IllegalArgumentException.class,
                () -> session.addPhoto(new byte[4 * W * H], bigger));
        assertTrue(e.getMessage().contains("not the session's 64x48"), e.getMessage());
        transport.reply(400, error("bad_board", "board spec does not match: no marker of DICT_5X5_100 found"));
        ServerRejectedException rejected = assertThrows(ServerRejectedException.class,
                () -> session.addPhoto(new byte[W * H], photo()));
        assertEquals(400, rejected.status);
        transport.reply(200, view("photo-3", new double[] {5, 5}).replace("\"width\":64", "\"width\":65"));
        assertEquals("width", assertThrows(io.lumipose.client.json.ContractException.class,
                () -> session.addPhoto(new byte[W * H], photo())).field);
    }

    @Test
    void theBoardsExposureHint() {
        assertEquals("too dark: more light on the board", CalibrationSession.exposureHint(12));
        assertNull(CalibrationSession.exposureHint(120));
        assertTrue(CalibrationSession.exposureHint(250).startsWith("too bright"));
    }

    /** What the screen keeps of a session (its file in the app's storage): read back equal, and usable. */
    @Test
    void aSessionSurvivesItsJsonAndGoesOn() throws Exception {
        transport.reply(200, view("photo-1", new double[] {5, 5}, new double[] {60, 40}))
                .reply(422, error("no_board", "no ChArUco corners found on the photo"))
                .reply(200, okReport(calibrated())).reply(200, calibrated().toJson().toString());
        session.addPhoto(new byte[W * H], photo());
        session.addPhoto(new byte[W * H], photo());
        DeviceProfile phone = DeviceProfile.ofPhone("phone", "phone", LensFacing.BACK, CAMERA, W, H);
        session.calibrate(phone, null); // the report's 2 x 3 grid is the session's from now on
        JSONObject saved = session.toJson();
        assertEquals(CalibrationSession.SCHEMA, saved.getString("schema"));

        FakeTransport later = new FakeTransport();
        CalibrationSession back = CalibrationSession.fromJson(new LumiposeClient(new ClientConfig(
                "http://server:8000", "key", "phone-1", false, new RetryPolicy(1, 0, 1.0, 0)), later, ms -> { }),
                saved.toString());
        assertTrue(saved.similar(back.toJson()), back.toJson().toString());
        assertEquals(BOARD.toJson().toString(), back.board().toJson().toString());
        assertEquals(2, back.photos());
        assertEquals(1, back.views().size());
        assertEquals(session.views().get(0).toJson().toString(), back.views().get(0).toJson().toString());
        assertEquals(2, back.coverage().rows, "the report's grid kept");
        assertEquals(3, back.coverage().columns);
        assertEquals(session.coverage().count(0, 0), back.coverage().count(0, 0));

        later.reply(200, view("photo-3", new double[] {33, 5})).reply(200, okReport(calibrated()))
                .reply(200, calibrated().toJson().toString());
        back.addPhoto(new byte[W * H], photo());
        assertEquals("http://server:8000/v1/calibrations/views?name=photo-3", later.calls.get(0).url);
        assertTrue(back.calibrate(phone, null).report.ok);
        assertEquals(2, body(later.calls.get(1)).getJSONArray("views").length(), "the restored view and the new one");
        assertThrows(IllegalArgumentException.class, () -> back.addPhoto(new byte[32 * 24],
                FrameMeta.builder(32, 24).camera(CAMERA).frameKind("pose").build()), "the session's size is kept");
    }

    @Test
    void anEmptySessionSurvivesItsJson() {
        CalibrationSession back = CalibrationSession.fromJson(null, session.toJson().toString());
        assertEquals(0, back.photos());
        assertNull(back.coverage());
        assertTrue(session.toJson().similar(back.toJson()));
    }

    /** A damaged or foreign file is refused naming what is wrong, never half read. */
    @Test
    void aDamagedSessionIsRefusedNamingWhatIsWrong() throws Exception {
        transport.reply(200, view("photo-1", new double[] {5, 5}, new double[] {60, 40}));
        session.addPhoto(new byte[W * H], photo());
        String good = session.toJson().toString();

        ContractException cut = assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, good.substring(0, good.length() - 3)));
        assertEquals("calibration session", cut.field);
        assertTrue(cut.getMessage().contains("not a JSON object"), cut.getMessage());
        assertEquals("schema", assertThrows(ContractException.class, () -> CalibrationSession.fromJson(null,
                new JSONObject(good).put("schema", "lumipose.survey-session/1").toString())).field);
        JSONObject board = new JSONObject(good);
        board.getJSONObject("board").put("squares_x", 1);
        ContractException b = assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, board.toString()));
        assertTrue(b.field.startsWith("board"), b.field);
        JSONObject corners = new JSONObject(good);
        corners.getJSONArray("views").getJSONObject(0).getJSONArray("corner_ids").put(0, 3000000);
        assertEquals("views[0].corner_ids[0]", assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, corners.toString())).field);
        assertEquals("views[0].width", assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, new JSONObject(good).put("width", W * 2).toString())).field);
        assertEquals("photos", assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, new JSONObject(good).put("photos", 0).toString())).field);
        assertEquals("grid_rows", assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, new JSONObject(good).put("grid_rows", 2).toString())).field);
        assertEquals("height", assertThrows(ContractException.class,
                () -> CalibrationSession.fromJson(null, withoutHeight(good))).field);
    }

    private static String withoutHeight(String json) {
        JSONObject o = new JSONObject(json);
        o.remove("height");
        return o.toString();
    }
}
