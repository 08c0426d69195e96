package io.lumipose.client.contract;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNotNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import java.io.IOException;
import java.math.BigDecimal;
import java.math.BigInteger;
import java.util.ArrayList;
import java.util.HashMap;
import java.util.HashSet;
import java.util.List;
import java.util.Map;
import java.util.Set;
import java.util.TreeSet;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.testutil.Repo;

/**
 * The Java bounds are the contract's: every bounded number of the exported JSON Schemas
 * (shared_schemas/json/, written from shared_schemas/models.py) has its {@link ContractRanges}
 * entry with the same ends, or is named here as one the app never sends. A bound added or changed
 * on the Python side fails this test until the Java side follows.
 */
class ContractRangesTest {
    /** "schema file#Model.field" -> the Java range that mirrors it. */
    private static final Map<String, ContractRanges.Range> MIRRORED = new HashMap<String, ContractRanges.Range>();
    /** Bounded numbers the app does not check, and why. */
    private static final Map<String, String> NOT_MIRRORED = new HashMap<String, String>();

    static {
        MIRRORED.put("frame#FrameMeta.width", ContractRanges.SIDE_PX);
        MIRRORED.put("frame#FrameMeta.height", ContractRanges.SIDE_PX);
        MIRRORED.put("frame#FrameMeta.row_stride", ContractRanges.ROW_STRIDE);
        MIRRORED.put("frame#FrameMeta.exposure_s", ContractRanges.EXPOSURE_S);
        MIRRORED.put("frame#FrameMeta.iso", ContractRanges.ISO);
        MIRRORED.put("frame#FrameMeta.rolling_shutter_skew_s", ContractRanges.ROLLING_SHUTTER_SKEW_S);
        MIRRORED.put("frame#FrameMeta.heading_deg", ContractRanges.ANGLE_DEG);
        MIRRORED.put("frame#FrameMeta.compass_bearing_deg", ContractRanges.ANGLE_DEG);
        MIRRORED.put("frame#FrameMeta.gravity_camera", ContractRanges.GRAVITY);
        MIRRORED.put("frame#FrameMeta.angular_velocity_camera_dps", ContractRanges.ANGULAR_RATE_DPS);
        MIRRORED.put("frame#CameraIntrinsics.fx", ContractRanges.FOCAL_PX);
        MIRRORED.put("frame#CameraIntrinsics.fy", ContractRanges.FOCAL_PX);
        MIRRORED.put("frame#CameraIntrinsics.cx", ContractRanges.PRINCIPAL_PX);
        MIRRORED.put("frame#CameraIntrinsics.cy", ContractRanges.PRINCIPAL_PX);
        MIRRORED.put("frame#CameraIntrinsics.distortion", ContractRanges.DISTORTION);
        MIRRORED.put("frame#CameraIntrinsics.pixel_size_m", ContractRanges.PIXEL_SIZE_M);
        MIRRORED.put("frame#CameraIntrinsics.focal_length_m", ContractRanges.FOCAL_LENGTH_M);
        MIRRORED.put("frame#Crop.x", ContractRanges.CROP_OFFSET_PX);
        MIRRORED.put("frame#Crop.y", ContractRanges.CROP_OFFSET_PX);
        MIRRORED.put("frame#Crop.full_width", ContractRanges.SIDE_PX);
        MIRRORED.put("frame#Crop.full_height", ContractRanges.SIDE_PX);
        MIRRORED.put("frame#Crop.levels_dn", ContractRanges.GREY_LEVEL_DN);
        MIRRORED.put("map#Beacon.center_m", ContractRanges.COORDINATE_M);
        MIRRORED.put("map#Beacon.yaw_deg", ContractRanges.ANGLE_DEG);
        MIRRORED.put("map#BeaconMap.bearing_deg", ContractRanges.ANGLE_DEG);
        MIRRORED.put("map#Beacon.side_m", ContractRanges.BEACON_SIZE_M);
        MIRRORED.put("map#Beacon.width_m", ContractRanges.BEACON_SIZE_M);
        MIRRORED.put("map#Beacon.height_m", ContractRanges.BEACON_SIZE_M);
        MIRRORED.put("map#Beacon.diameter_m", ContractRanges.BEACON_SIZE_M);
        MIRRORED.put("map#Beacon.corner_radius_m", ContractRanges.CORNER_RADIUS_M);
        NOT_MIRRORED.put("frame#FrameMeta.timestamp_ns", "[0, 2^63): checked by timestampIsAnyNonNegativeLong");
        NOT_MIRRORED.put("frame#GroundTruth.position_m", "ground truth: simulator and test-bench fixtures only");
        NOT_MIRRORED.put("frame#GroundTruth.rotation_wc", "ground truth: simulator and test-bench fixtures only");
        NOT_MIRRORED.put("map#Beacon.id", "a VLC code, not a measurement: the server checks [0, 255]");
        NOT_MIRRORED.put("map#BeaconMap.required_sigma_m", "the server's refusal threshold; the app never reads it");
    }

    private static JSONObject schema(String name) throws IOException {
        return new JSONObject(Repo.text("shared_schemas/json/" + name + ".schema.json"));
    }

    /** The innermost bounded schema of a property: its non-null branch, then its items. */
    private static JSONObject bounded(JSONObject property) {
        JSONObject s = property;
        if (s.has("anyOf")) {
            JSONArray branches = s.getJSONArray("anyOf");
            JSONObject only = null;
            for (int i = 0; i < branches.length(); i++) {
                JSONObject branch = branches.getJSONObject(i);
                if (!"null".equals(branch.optString("type"))) {
                    if (only != null) {
                        return null; // a choice of models, each checked on its own
                    }
                    only = branch;
                }
            }
            s = only;
        }
        while (s != null && s.has("items") && s.get("items") instanceof JSONObject) {
            s = s.getJSONObject("items");
        }
        boolean hasBound = s != null && (s.has("minimum") || s.has("maximum") || s.has("exclusiveMinimum")
                || s.has("exclusiveMaximum"));
        return hasBound ? s : null;
    }

    /** "file#Model.field" -> its bounded schema, for every bounded number of the exported schemas. */
    private static Map<String, JSONObject> boundedNumbers() throws IOException {
        Map<String, JSONObject> out = new HashMap<String, JSONObject>();
        for (String file : new String[] {"frame", "map"}) {
            JSONObject root = schema(file);
            List<JSONObject> models = new ArrayList<JSONObject>();
            models.add(root);
            JSONObject defs = root.optJSONObject("$defs");
            if (defs != null) {
                for (String name : defs.keySet()) {
                    models.add(defs.getJSONObject(name));
                }
            }
            for (JSONObject model : models) {
                JSONObject properties = model.optJSONObject("properties");
                if (properties == null) {
                    continue;
                }
                for (String field : properties.keySet()) {
                    JSONObject b = bounded(properties.getJSONObject(field));
                    if (b != null) {
                        out.put(file + "#" + model.getString("title") + "." + field, b);
                    }
                }
            }
        }
        return out;
    }

    @Test
    void everyBoundOfTheSchemasIsMirroredWithTheSameEnds() throws IOException {
        Map<String, JSONObject> numbers = boundedNumbers();
        Set<String> unaccounted = new TreeSet<String>(numbers.keySet());
        unaccounted.removeAll(MIRRORED.keySet());
        unaccounted.removeAll(NOT_MIRRORED.keySet());
        assertTrue(unaccounted.isEmpty(), "bounded in the contract, not in ContractRanges: " + unaccounted);
        Set<String> stale = new TreeSet<String>(MIRRORED.keySet());
        stale.addAll(NOT_MIRRORED.keySet());
        stale.removeAll(numbers.keySet());
        assertTrue(stale.isEmpty(), "not bounded (or gone) in the contract's schemas: " + stale);
        for (Map.Entry<String, ContractRanges.Range> e : MIRRORED.entrySet()) {
            JSONObject b = numbers.get(e.getKey());
            assertFalse(b.has("exclusiveMinimum") || b.has("exclusiveMaximum"),
                    e.getKey() + ": the schema excludes an end, a Java Range includes both");
            assertEquals(b.getDouble("minimum"), e.getValue().min, 0.0, e.getKey() + " minimum");
            assertEquals(b.getDouble("maximum"), e.getValue().max, 0.0, e.getKey() + " maximum");
        }
    }

    @Test
    void timestampIsAnyNonNegativeLong() throws IOException {
        JSONObject b = bounded(schema("frame").getJSONObject("properties").getJSONObject("timestamp_ns"));
        assertNotNull(b);
        assertEquals(ContractRanges.MIN_TIMESTAMP_NS, b.getLong("minimum"));
        BigDecimal end = new BigDecimal(b.get("exclusiveMaximum").toString());
        assertEquals(new BigDecimal(BigInteger.valueOf(Long.MAX_VALUE).add(BigInteger.ONE)), end,
                "timestamp_ns ends at 2^63, Java's long");
    }

    private static JSONObject goldenFrame() throws IOException {
        return new JSONObject(Repo.text("shared_schemas/examples/frame.json"));
    }

    private static String refusedField(JSONObject frame) {
        return assertThrows(ContractException.class, () -> FrameMeta.fromJson(frame.toString())).field;
    }

    @Test
    void framesWithTheProbesNumbersAreRefusedNamingTheField() throws IOException {
        Object[][] cases = {
            {"camera", "fx", 1e308, "camera.fx"},
            {"camera", "fx", 1e-300, "camera.fx"},
            {"camera", "cx", 1e308, "camera.cx"},
            {"camera", "cx", 3 * 970.0, "camera.cx"},
            {"camera", "distortion", new JSONArray(new double[] {1e300, 0, 0, 0, 0}), "camera.distortion[0]"},
            {"camera", "distortion", new JSONArray(new double[] {1e10, 1e10, 1e10, 1e10, 1e10, 1e10, 1e10, 1e10}),
                "camera.distortion[0]"},
            {"camera", "distortion", new JSONArray(new double[] {0.1, 0.1, 0.1}), "camera.distortion"},
            {"camera", "pixel_size_m", 1.0, "camera.pixel_size_m"},
            {"camera", "focal_length_m", 1e-300, "camera.focal_length_m"},
            {null, "gravity_camera", new JSONArray(new double[] {1e200, 1e200, 1e200}), "gravity_camera[0]"},
            {null, "gravity_camera", new JSONArray(new double[] {1e-300, 0, 0}), "gravity_camera"},
            {null, "angular_velocity_camera_dps", new JSONArray(new double[] {0, 1e300, 0}),
                "angular_velocity_camera_dps[1]"},
            {null, "timestamp_ns", new BigInteger("1" + new String(new char[400]).replace('\0', '0')),
                "timestamp_ns"},
            {null, "timestamp_ns", -1L, "timestamp_ns"},
            {null, "width", 100_001, "width"},
            {null, "row_stride", 4_294_968_266L, "row_stride"}, // 2^32 + 970: int truncation would give 970
            {null, "exposure_s", 1e-300, "exposure_s"},
            {null, "iso", 1e300, "iso"},
            {null, "rolling_shutter_skew_s", 2.0, "rolling_shutter_skew_s"},
            {null, "heading_deg", 1e300, "heading_deg"},
            {null, "compass_bearing_deg", -361.0, "compass_bearing_deg"},
            {null, "crop", new JSONObject("{\"x\": 0, \"y\": 0, \"full_width\": 100001, \"full_height\": 1296}"),
                "crop.full_width"},
            {null, "crop", new JSONObject("{\"x\": 1, \"y\": 0, \"full_width\": 970, \"full_height\": 1296}"), "crop"},
        };
        for (Object[] c : cases) {
            JSONObject frame = goldenFrame();
            JSONObject target = c[0] == null ? frame : frame.getJSONObject((String) c[0]);
            target.put((String) c[1], c[2]);
            assertEquals(c[3], refusedField(frame), c[1] + " = " + c[2]);
        }
    }

    @Test
    void theEndsOfTheRangesAreAccepted() throws IOException {
        JSONObject frame = goldenFrame();
        frame.getJSONObject("camera").put("fx", 1.0).put("fy", 1e6).put("cx", -970.0).put("cy", 2592.0)
                .put("distortion", new JSONArray(new double[] {1000, -1000, 1000, -1000, 1000, -1000, 1000, -1000}));
        frame.put("gravity_camera", new JSONArray(new double[] {100, -100, 100})).put("timestamp_ns", Long.MAX_VALUE)
                .put("heading_deg", -360.0).put("compass_bearing_deg", 360.0).put("exposure_s", 1e-9)
                .put("rolling_shutter_skew_s", 0.0)
                .put("angular_velocity_camera_dps", new JSONArray(new double[] {4000, -4000, 0}));
        FrameMeta meta = FrameMeta.fromJson(frame.toString());
        assertEquals(Long.MAX_VALUE, (long) meta.timestampNs);
        assertEquals(360.0, meta.compassBearingDeg, 0.0);
        assertEquals(360.0, FrameMeta.fromJson(meta.toJson()).compassBearingDeg, 0.0, "written back");
        JSONObject cropped = goldenFrame().put("width", 100).put("height", 100).put("row_stride", 100)
                .put("crop", new JSONObject("{\"x\": 2000, \"y\": 3000, \"full_width\": 3024, \"full_height\": 4032}"));
        cropped.getJSONObject("camera").put("cx", 1511.5).put("cy", 2015.5);
        assertEquals(2000, FrameMeta.fromJson(cropped.toString()).toJson().getJSONObject("crop").getInt("x"),
                "a window's principal point is the full frame's");
        FrameMeta.fromJson(Repo.text("shared_schemas/examples/frame_profile_nv21.json"));
    }

    @Test
    void mapsWithNumbersOutOfRangeAreRefused() throws IOException {
        String map = Repo.text("shared_schemas/examples/map.json");
        RoomMap.fromJson(map);
        Set<String> fields = new HashSet<String>();
        for (String[] c : new String[][] {{"side_m", "1e-300"}, {"side_m", "1e308"}, {"yaw_deg", "1e300"},
            {"corner_radius_m", "1e300"}}) {
            JSONObject o = new JSONObject(map);
            o.getJSONArray("beacons").getJSONObject(0).put(c[0], Double.parseDouble(c[1]));
            fields.add(assertThrows(ContractException.class, () -> RoomMap.fromJson(o.toString())).field);
        }
        JSONObject turned = new JSONObject(map).put("bearing_deg", 400.0);
        fields.add(assertThrows(ContractException.class, () -> RoomMap.fromJson(turned.toString())).field);
        assertEquals(-360.0, RoomMap.fromJson(new JSONObject(map).put("bearing_deg", -360.0).toString()).bearingDeg,
                0.0);
        JSONObject far = new JSONObject(map);
        far.getJSONArray("beacons").getJSONObject(0).put("center_m", new JSONArray(new double[] {0, 0, 1e308}));
        fields.add(assertThrows(ContractException.class, () -> RoomMap.fromJson(far.toString())).field);
        assertEquals(new TreeSet<String>(java.util.Arrays.asList("bearing_deg", "beacons[0].side_m",
                "beacons[0].yaw_deg",
                "beacons[0].corner_radius_m", "beacons[0].center_m[2]")), new TreeSet<String>(fields));
    }

    @Test
    void shapedBeaconsSizesOutOfRangeAreRefusedNamingTheField() throws IOException {
        String map = Repo.text("shared_schemas/examples/map_shapes.json");
        RoomMap.fromJson(map);
        // beacon 1 is a rectangle, beacon 2 a circle
        Object[][] cases = {{1, "width_m", 1e-300}, {1, "width_m", 10.5}, {1, "height_m", 0.004},
            {1, "height_m", 1e308}, {2, "diameter_m", 0.004}, {2, "diameter_m", 1e308}};
        for (Object[] c : cases) {
            JSONObject o = new JSONObject(map);
            o.getJSONArray("beacons").getJSONObject((Integer) c[0]).put((String) c[1], c[2]);
            assertEquals("beacons[" + c[0] + "]." + c[1],
                    assertThrows(ContractException.class, () -> RoomMap.fromJson(o.toString())).field,
                    c[1] + " = " + c[2]);
        }
    }

    @Test
    void theJavaShapesAreTheContractsPanelShapes() throws IOException {
        JSONArray values = schema("map").getJSONObject("$defs").getJSONObject("PanelShape").getJSONArray("enum");
        assertEquals(new TreeSet<Object>(java.util.Arrays.asList(Beacon.ROUNDED_RECTANGLE, Beacon.CIRCLE)),
                new TreeSet<Object>(values.toList()));
        JSONObject shape = schema("map").getJSONObject("$defs").getJSONObject("Beacon").getJSONObject("properties")
                .getJSONObject("shape");
        assertEquals(Beacon.ROUNDED_RECTANGLE, shape.getString("default"), "a beacon without a shape is a");
    }
}
