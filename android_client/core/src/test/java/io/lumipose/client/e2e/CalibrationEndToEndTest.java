package io.lumipose.client.e2e;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.AfterAll;
import org.junit.jupiter.api.BeforeAll;
import org.junit.jupiter.api.Test;

import io.lumipose.client.calibration.BoardSpec;
import io.lumipose.client.calibration.CalibrationSession;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.RetryPolicy;
import io.lumipose.client.sensor.LensFacing;
import io.lumipose.client.testutil.EndToEnd;
import io.lumipose.client.testutil.Lumipose;
import io.lumipose.client.testutil.Python;

/**
 * The calibration screen's session against a real {@code lumipose serve}: board photos rendered
 * through a known pinhole by the simulator (resources/calibration/board_photos.py: {@code simulator.board}'s
 * good pose set and renderer, with blur and noise) go up as the app sends them, a blank photo is refused as
 * having no board,
 * and the calibration must find the pinhole (fx, fy within 0.5 %, cx, cy within 2 px: at least
 * twelve of 32 views of a 640 x 480 camera) and store the profile, which the server then serves.
 */
class CalibrationEndToEndTest {
    private static final BoardSpec BOARD = new BoardSpec(7, 5, 0.03, 0.022, null);
    /** The phone's datasheet: a few percent off the rendered pinhole, as a datasheet is. */
    private static final Intrinsics DATASHEET = new Intrinsics(620, 620, 319.5, 239.5, null, 1.4e-6, 8.68e-4, "e2e");
    private static Lumipose.Serve serve;
    private static Path photos;

    @BeforeAll
    static void start() throws Exception {
        EndToEnd.assumeExecutable();
        serve = Lumipose.Serve.start();
        photos = Files.createTempDirectory("lumipose-board");
        Python.run("calibration/board_photos.py", photos.toString(), BOARD.toJson().toString());
    }

    @AfterAll
    static void stop() throws Exception {
        if (serve != null) {
            serve.close();
        }
    }

    private static FrameMeta meta(int width, int height) {
        return FrameMeta.builder(width, height).camera(DATASHEET).exposureS(0.02).iso(800.0).frameKind("pose")
                .gravityCamera(new double[] {0, 0.3, 9.8}).build();
    }

    /** board_photos.py's truth.json in {@code dir}. */
    private static JSONObject truth(Path dir) throws Exception {
        return new JSONObject(new String(Files.readAllBytes(dir.resolve("truth.json")), StandardCharsets.UTF_8));
    }

    private static LumiposeClient client(String deviceId) {
        return LumiposeClient.create(new ClientConfig(serve.baseUrl, Lumipose.Serve.KEY, deviceId, false,
                new RetryPolicy(2, 200, 2.0, 1000)));
    }

    @Test
    void theRenderedPinholeIsFoundAndItsProfileStored() throws Exception {
        JSONObject truth = truth(photos);
        int w = truth.getInt("width");
        int h = truth.getInt("height");
        LumiposeClient client = client("e2e-phone");
        CalibrationSession session = new CalibrationSession(client, BOARD);

        CalibrationSession.Photo blank = session.addPhoto(Files.readAllBytes(photos.resolve("blank.y")), meta(w, h));
        assertFalse(blank.found(), "a photo without a board");
        assertNotNull(blank.refusal);
        JSONArray names = truth.getJSONArray("photos");
        int found = 0;
        for (int i = 0; i < names.length(); i++) {
            byte[] luma = Files.readAllBytes(photos.resolve(names.getString(i) + ".y"));
            // a board mostly outside the frame may show too few corners: refused, as on a phone
            found += session.addPhoto(luma, meta(w, h)).found() ? 1 : 0;
        }
        assertTrue(found >= 12, found + " of " + names.length() + " photos with the board found");
        assertEquals(found, session.views().size());
        assertTrue(session.coverage().coverage() > 0.5, "the views spread over the frame: " + session.coverage()
                .coverage());

        DeviceProfile phone = DeviceProfile.ofPhone("e2e-phone", "e2e phone", LensFacing.BACK, DATASHEET, w, h);
        CalibrationSession.Outcome o = session.calibrate(phone, null);
        assertTrue(o.report.ok, "refused: " + o.report.message + " " + o.report.advice);
        DeviceProfile.MeasuredPinhole k = o.report.profile.intrinsics;
        System.out.printf(java.util.Locale.US, "calibration e2e: %d views, fx %.3f fy %.3f cx %.3f cy %.3f px "
                + "(truth %.1f %.1f %.1f %.1f), rms %.3f px%n", found, k.fx, k.fy, k.cx, k.cy, truth.getDouble("fx"),
                truth.getDouble("fy"), truth.getDouble("cx"), truth.getDouble("cy"), o.report.rmsPx);
        assertEquals(truth.getDouble("fx"), k.fx, 0.005 * truth.getDouble("fx"));
        assertEquals(truth.getDouble("fy"), k.fy, 0.005 * truth.getDouble("fy"));
        assertEquals(truth.getDouble("cx"), k.cx, 2.0);
        assertEquals(truth.getDouble("cy"), k.cy, 2.0);
        assertEquals(w, o.report.profile.width);
        assertTrue(o.stored, "stored: " + o.storeError);
        assertEquals("e2e-phone-calibrated", o.report.profile.id);

        DeviceProfile served = DeviceProfile.fromJson(client.sendJson("GET", CalibrationSession.PROFILES_PATH
                + o.report.profile.id, null));
        assertEquals(k.fx, served.intrinsics.fx, 0.0);
        // The frames of this camera carry the calibration: at the photos' size, exactly its pinhole.
        assertEquals(k.cx, served.forFrame(w, h).cx, 1e-9);
    }

    /**
     * Issue 29: a board the user owns (DICT_4X4_1000, markers from id 10) seen by a front camera whose
     * photos are mirrored. The real server finds each view mirrored, the app keeps that and sends it
     * back, and the report says the photos were un-mirrored: the fit is of the lens, whose cx (322 px)
     * a fit of the mirrored photos would put at 317 px.
     */

    @Test
    void aFrontCamerasMirroredPhotosOfAnotherBoardCalibrateTheLens() throws Exception {
        BoardSpec owned = new BoardSpec(BoardSpec.CHARUCO, 7, 5, 0.03, 0.022, "DICT_4X4_1000", false, 10, false);
        Path dir = Files.createTempDirectory("lumipose-mirrored");
        Python.run("calibration/board_photos.py", dir.toString(), owned.toJson().toString(), "32", "mirrored");
        JSONObject truth = truth(dir);
        int w = truth.getInt("width");
        int h = truth.getInt("height");
        CalibrationSession session = new CalibrationSession(client("e2e-front"), owned);
        JSONArray names = truth.getJSONArray("photos");
        for (int i = 0; i < names.length(); i++) {
            CalibrationSession.Photo p = session.addPhoto(Files.readAllBytes(dir.resolve(names.getString(i) + ".y")),
                    meta(w, h));
            assertTrue(!p.found() || p.view.mirrored && !p.view.inverted, p.name + " found as it is");
        }
        int found = session.views().size();
        assertTrue(found >= 12, found + " of " + names.length() + " photos with the board found");

        DeviceProfile phone = DeviceProfile.ofPhone("e2e-front", "e2e front camera", LensFacing.FRONT, DATASHEET, w, h);
        CalibrationSession.Outcome o = session.calibrate(phone, null);
        assertTrue(o.report.ok, "refused: " + o.report.message + " " + o.report.advice);
        assertTrue(o.report.message.contains("photos were mirrored: un-mirrored before fitting (" + found + " of "
                + found + ")"), o.report.message);
        assertTrue(o.report.fitted.trusted);
        DeviceProfile.MeasuredPinhole k = o.report.profile.intrinsics;
        System.out.printf(java.util.Locale.US, "mirrored calibration e2e: %d views, fx %.3f cx %.3f cy %.3f px "
                + "(truth %.1f %.1f %.1f)%n", found, k.fx, k.cx, k.cy, truth.getDouble("fx"), truth.getDouble("cx"),
                truth.getDouble("cy"));
        assertEquals(truth.getDouble("fx"), k.fx, 0.005 * truth.getDouble("fx"));
        assertEquals(truth.getDouble("cx"), k.cx, 2.0, "the lens's cx, not the mirrored photo's");
        assertEquals(truth.getDouble("cy"), k.cy, 2.0);
        assertEquals(k.fx, o.report.fitted.fx, 0.0);
    }
}
