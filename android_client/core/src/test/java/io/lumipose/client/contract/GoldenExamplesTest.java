package io.lumipose.client.contract;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertTrue;
import static org.junit.jupiter.api.Assertions.fail;

import java.util.HashSet;
import java.util.Iterator;
import java.util.Set;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.ServerRejectedException;
import io.lumipose.client.protocol.CaptureProtocol;
import io.lumipose.client.testutil.Repo;

/** The client reads and writes exactly what shared_schemas/ (the contract's source of truth) says. */
class GoldenExamplesTest {
    private static final String EXAMPLES = "shared_schemas/examples/";

    /** Same JSON up to number formatting (1 vs 1.0) and 1e-12 relative float noise. */
    private static void assertSameJson(Object expected, Object actual, String path) {
        if (expected instanceof JSONObject) {
            if (!(actual instanceof JSONObject)) {
                fail(path + ": expected an object, got " + actual);
            }
            JSONObject e = (JSONObject) expected;
            JSONObject a = (JSONObject) actual;
            assertEquals(e.keySet(), a.keySet(), path + " keys");
            for (String k : e.keySet()) {
                assertSameJson(e.get(k), a.get(k), path + "." + k);
            }
        } else if (expected instanceof JSONArray) {
            JSONArray e = (JSONArray) expected;
            JSONArray a = (JSONArray) actual;
            assertEquals(e.length(), a.length(), path + " length");
            for (int i = 0; i < e.length(); i++) {
                assertSameJson(e.get(i), a.get(i), path + "[" + i + "]");
            }
        } else if (expected instanceof Number) {
            double e = ((Number) expected).doubleValue();
            double a = ((Number) actual).doubleValue();
            assertEquals(e, a, Math.abs(e) * 1e-12, path);
        } else {
            assertEquals(expected, actual, path);
        }
    }

    @Test
    void frameExampleRoundTripsUnchanged() throws Exception {
        // (frame_cropped.json is as the Python client sends it: without row_stride, which the app always writes)
        for (String name : new String[] {"frame.json", "frame_profile_nv21.json", "frame_id.json"}) {
            JSONObject golden = new JSONObject(Repo.text(EXAMPLES + name));
            JSONObject written = FrameMeta.fromJson(golden).toJson();
            // The client always writes row_stride and the intrinsics' distortion; the examples do too.
            assertSameJson(golden, written, name);
        }
    }

    @Test
    void frameExampleFieldsReadAsTheContractMeans() throws Exception {
        FrameMeta m = FrameMeta.fromJson(Repo.text(EXAMPLES + "frame.json"));
        assertEquals(970, m.width);
        assertEquals(1296, m.height);
        assertEquals(970L * 1296, m.frameBytes());
        assertEquals(484.5, m.camera.cx, 0);
        assertEquals(0.01, m.exposureS, 0);
        FrameMeta nv21 = FrameMeta.fromJson(Repo.text(EXAMPLES + "frame_profile_nv21.json"));
        assertEquals("xiaomi-mi8-rear", nv21.cameraProfile);
        assertNull(nv21.camera);
        assertEquals(3072L * 4032 * 3 / 2, nv21.frameBytes());
        assertEquals(12.5, nv21.headingDeg, 0);
    }

    @Test
    void captureProtocolFrameExamplesReadAsTheContractMeans() throws Exception {
        JSONObject idJson = new JSONObject(Repo.text(EXAMPLES + "frame_id.json"));
        FrameMeta id = FrameMeta.fromJson(idJson);
        assertEquals("id", id.frameKind);
        assertEquals(idJson.getDouble("exposure_s"), id.exposureS, 0);
        assertTrue(id.exposureS * 1e9 <= CaptureProtocol.ID_MAX_EXPOSURE_NS, "an ID frame the server reads");
        assertEquals(idJson.getDouble("rolling_shutter_skew_s"), id.rollingShutterSkewS, 0);
        assertTrue(id.rollingShutterSkewS > 0 && id.timestampNs != null, "ID frames need their row timing");
        JSONObject croppedJson = new JSONObject(Repo.text(EXAMPLES + "frame_cropped.json"));
        FrameMeta cropped = FrameMeta.fromJson(croppedJson);
        JSONObject crop = croppedJson.getJSONObject("crop");
        assertEquals("pose", cropped.frameKind);
        assertTrue(cropped.width < crop.getInt("full_width") && cropped.height < crop.getInt("full_height"));
        // similar(): numbers by value (the file's 53.0 parses as a BigDecimal, FrameMeta writes a Double)
        assertTrue(crop.similar(cropped.toJson().getJSONObject("crop")), "the crop block is sent on: "
                + cropped.toJson().getJSONObject("crop"));
    }

    @Test
    void bundledFixtureMetadataParses() throws Exception {
        FrameMeta m = FrameMeta.fromJson(Repo.text("tests/fixtures/bench_1m.json"));
        assertEquals(m.frameBytes(), java.nio.file.Files.size(Repo.file("tests/fixtures/bench_1m.y")));
    }

    @Test
    void whatTheAppSendsUsesOnlyFieldsTheJsonSchemaDeclares() throws Exception {
        JSONObject schema = new JSONObject(Repo.text("shared_schemas/json/frame.schema.json"));
        JSONObject cameraSchema = schema.getJSONObject("$defs").getJSONObject("CameraIntrinsics");
        CameraFacts facts = Devices.load(Devices.FRONT_270);
        CapturePlan plan = CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 125_000L, 4, 2.0, 1_300_000L));
        FrameDescriber describer = new FrameDescriber(facts, plan, 90.0);
        JSONObject pose = describer.describe(FrameResult.builder(1L).request("pose")
                .exposureNs(plan.pose.exposureNs).sensitivityIso(plan.pose.sensitivityIso)
                .rollingShutterSkewNs(30_000_000L).build(), new float[] {0, 0, 9.81f},
                new float[] {1, 0, 0, 0, 1, 0, 0, 0, 1}).meta.toJson();
        assertDeclared(schema, pose, "frame");
        assertDeclared(cameraSchema, pose.getJSONObject("camera"), "camera");
        JSONObject id = describer.describe(FrameResult.builder(2L).request("id")
                .exposureNs(plan.id.exposureNs).sensitivityIso(plan.id.sensitivityIso)
                .rollingShutterSkewNs(30_000_000L).build(), null, null).meta.toJson();
        assertDeclared(schema, id, "ID frame");
        JSONArray kinds = schema.getJSONObject("$defs").getJSONObject("FrameKind").getJSONArray("enum");
        assertTrue(kinds.toList().contains(id.getString("frame_kind")), "frame_kind values: " + kinds);
        JSONArray curves = schema.getJSONObject("$defs").getJSONObject("ToneCurve").getJSONArray("enum");
        assertTrue(curves.toList().contains(pose.getString("tone_curve")), "tone_curve values: " + curves);
    }

    private static void assertDeclared(JSONObject schema, JSONObject sent, String what) {
        Set<String> declared = new HashSet<>(schema.getJSONObject("properties").keySet());
        for (Iterator<String> it = sent.keys(); it.hasNext(); ) {
            String k = it.next();
            assertTrue(declared.contains(k), what + " field '" + k + "' is not in the JSON Schema");
        }
        JSONArray required = schema.getJSONArray("required");
        for (int i = 0; i < required.length(); i++) {
            assertTrue(sent.has(required.getString(i)), what + " lacks required '" + required.getString(i) + "'");
        }
    }

    @Test
    void okResultExampleParses() throws Exception {
        LocateResult r = LocateResult.fromJson(Repo.text(EXAMPLES + "result_ok.json"));
        assertTrue(r.ok);
        assertEquals(3, r.positionM().length);
        assertEquals(0.15, r.positionM()[0], 0.01);
        assertEquals(0, r.beaconId.intValue());
        assertEquals("single_beacon_map", r.beaconIdSource);
        assertEquals(3, r.rotationWc().length);
        assertEquals(2, r.centerPx().length);
        assertNull(r.reason);
    }

    @Test
    void okResultExampleCarriesItsUncertainty() throws Exception {
        LocateResult r = LocateResult.fromJson(Repo.text(EXAMPLES + "result_ok.json"));
        double[] sigma = r.positionSigmaM();
        double[][] covariance = r.positionCovarianceM2();
        assertEquals(3, sigma.length);
        assertEquals(3, covariance.length);
        for (int i = 0; i < 3; i++) {
            assertEquals(Math.sqrt(covariance[i][i]), sigma[i], sigma[i] * 1e-12, "sigma = sqrt of the diagonal");
            for (int j = 0; j < 3; j++) {
                assertEquals(covariance[i][j], covariance[j][i], 0, "symmetric");
            }
        }
        double[] ellipse = r.errorEllipse95XyM();
        assertTrue(ellipse[0] >= ellipse[1] && ellipse[1] > 0, "semi-axes " + ellipse[0] + ", " + ellipse[1]);
        assertTrue(ellipse[0] < 0.01, "the 95 % ellipse of a 1 m fix is millimetres: " + ellipse[0]);
        LocateResult refused = LocateResult.fromJson(Repo.text(EXAMPLES + "result_no_fix.json"));
        assertNull(refused.positionSigmaM());
        assertNull(refused.positionCovarianceM2());
        assertNull(refused.errorEllipse95XyM());
    }

    @Test
    void theVlcAndTrackResultExampleReadsEveryField() throws Exception {
        JSONObject golden = new JSONObject(Repo.text(EXAMPLES + "result_vlc_track.json"));
        LocateResult r = LocateResult.fromJson(golden);
        assertTrue(r.ok);
        assertEquals("vlc", r.beaconIdSource);
        JSONObject vlc = golden.getJSONObject("vlc");
        assertEquals(vlc.getInt("beacon_id"), r.vlc().beaconId.intValue());
        assertEquals(r.beaconId, r.vlc().beaconId, "the fix's ID is the one read");
        assertEquals(vlc.getDouble("confidence"), r.vlc().confidence, 0);
        assertEquals(vlc.getBoolean("confident"), r.vlc().confident);
        assertEquals(vlc.getInt("frames"), r.vlc().frames);
        assertEquals(vlc.getDouble("chips_seen"), r.vlc().chipsSeen, 0);
        assertEquals(vlc.getInt("candidates"), r.vlc().candidates);
        JSONObject track = golden.getJSONObject("track");
        assertArrayEquals(doubles(track.getJSONArray("filtered_position_m")), r.track().filteredPositionM(), 0);
        assertArrayEquals(doubles(track.getJSONArray("velocity_mps")), r.track().velocityMps(), 0);
        assertEquals(track.getBoolean("outlier"), r.track().outlier);
        assertEquals(track.getBoolean("beacon_id_carried"), r.track().beaconIdCarried);
        assertEquals(golden.getInt("beacons_in_view"), r.beaconsInView().intValue());
        assertEquals(golden.getDouble("ambiguity_ratio"), r.ambiguityRatio, 0);
        JSONArray corners = golden.getJSONArray("corners_px");
        assertEquals(4, r.cornersPx().length);
        for (int i = 0; i < 4; i++) {
            assertArrayEquals(doubles(corners.getJSONArray(i)), r.cornersPx()[i], 0);
        }
        JSONObject timing = golden.getJSONObject("timing_ms");
        assertEquals(timing.keySet(), r.timingMs().keySet());
        assertEquals(timing.getDouble("total"), r.timingMs().get("total"), 0);
    }

    @Test
    void theVlcAndTrackExampleCarriesEveryFieldOfTheContractsResult() throws Exception {
        // a field added to the contract's result needs a golden example (and a reader above) too
        JSONObject schema = new JSONObject(Repo.text("shared_schemas/json/result.schema.json"));
        JSONObject golden = new JSONObject(Repo.text(EXAMPLES + "result_vlc_track.json"));
        assertEquals(schema.getJSONObject("properties").keySet(), golden.keySet());
    }

    private static double[] doubles(JSONArray a) {
        double[] out = new double[a.length()];
        for (int i = 0; i < out.length; i++) {
            out[i] = a.getDouble(i);
        }
        return out;
    }

    @Test
    void refusedResultExampleParses() throws Exception {
        LocateResult r = LocateResult.fromJson(Repo.text(EXAMPLES + "result_no_fix.json"));
        assertFalse(r.ok);
        assertEquals("beacon_cut_off", r.reason);
        assertNull(r.positionM());
        assertTrue(r.message.contains("border"));
    }

    @Test
    void errorExampleBecomesAnExceptionNamingTheField() throws Exception {
        ServerRejectedException e = ServerRejectedException.fromBody(400, Repo.text(EXAMPLES + "error.json"));
        assertEquals(400, e.status);
        assertEquals("bad_frame", e.code);
        assertEquals("row_stride", e.field);
        assertTrue(e.getMessage().contains("1257120"));
    }

    @Test
    void mapExamplesParse() throws Exception {
        RoomMap office = RoomMap.fromJson(Repo.text(EXAMPLES + "map.json"));
        assertEquals(4, office.beacons.size());
        assertArrayEquals(new double[] {1.8, 2.7, 2.72}, office.beacon(22).centerM(), 0);
        assertEquals(0.02, office.beacon(22).cornerRadiusM, 0);
        RoomMap demo = RoomMap.fromJson(Repo.text("shared_schemas/maps/demo.json"));
        assertEquals(Beacon.ROUNDED_RECTANGLE, demo.beacon(0).shape);
        assertEquals(0.174, demo.beacon(0).widthM, 0);
        assertEquals(0.174, demo.beacon(0).heightM, 0);
    }

    @Test
    void shapesMapExampleParses() throws Exception {
        RoomMap shapes = RoomMap.fromJson(Repo.text(EXAMPLES + "map_shapes.json"));
        Beacon square = shapes.beacon(3);
        assertEquals(Beacon.ROUNDED_RECTANGLE, square.shape);
        assertEquals(0.174, square.widthM, 0);
        assertEquals(0.174, square.heightM, 0);
        Beacon rectangle = shapes.beacon(12);
        assertEquals(Beacon.ROUNDED_RECTANGLE, rectangle.shape);
        assertEquals(1.195, rectangle.widthM, 0);
        assertEquals(0.295, rectangle.heightM, 0);
        assertEquals(0.01, rectangle.cornerRadiusM, 0);
        assertEquals(90, rectangle.yawDeg, 0);
        assertTrue(rectangle.hasCorners());
        Beacon circle = shapes.beacon(40);
        assertEquals(Beacon.CIRCLE, circle.shape);
        assertEquals(0.2, circle.widthM, 0);
        assertFalse(circle.hasCorners());
        assertEquals(0.1, circle.outlineRadiusM(), 0);
    }

    @Test
    void everyExampleIsReadHere() throws Exception {
        Set<String> names = new java.util.TreeSet<String>();
        try (java.nio.file.DirectoryStream<java.nio.file.Path> files =
                java.nio.file.Files.newDirectoryStream(Repo.root().resolve(EXAMPLES), "*.json")) {
            for (java.nio.file.Path f : files) {
                names.add(f.getFileName().toString());
            }
        }
        assertEquals(new java.util.TreeSet<String>(java.util.Arrays.asList("error.json", "frame.json",
                "frame_cropped.json", "frame_id.json", "frame_profile_nv21.json", "map.json", "map_shapes.json",
                "result_no_fix.json", "result_ok.json", "result_vlc_track.json")),
                names, "a new golden example needs a test here");
    }
}
