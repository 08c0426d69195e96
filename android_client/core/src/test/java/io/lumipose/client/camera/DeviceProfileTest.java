package io.lumipose.client.camera;

import static org.junit.jupiter.api.Assertions.assertArrayEquals;
import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;

import org.json.JSONArray;
import org.json.JSONObject;
import org.junit.jupiter.api.Test;
import org.junit.jupiter.api.io.TempDir;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.sensor.LensFacing;
import io.lumipose.client.testutil.Python;
import io.lumipose.client.testutil.Repo;

class DeviceProfileTest {
    private static DeviceProfile calibrated(int width, int height) {
        return new DeviceProfile("mi8-front-calibrated", "Mi 8 front", "S5K3T1", "front", 9e-7, 3.52e-3, width, height,
                new double[] {0.05, -0.1, 0.001, -0.002, 0.02}, 0.1,
                new DeviceProfile.MeasuredPinhole(3925.3, 3921.8, 1946.2, 2585.9, 0.18, 20));
    }

    /**
     * The app's scaling of a profile to a frame is the server's (server/camera.py,
     * intrinsics_from_profile): the same numbers for the calibration's own size, a quarter of it,
     * another aspect (centre-cropped) and a datasheet profile.
     */
    @Test
    void scaledToAFrameAsTheServerScalesIt(@TempDir Path dir) throws Exception {
        DeviceProfile measured = calibrated(3880, 5184);
        DeviceProfile datasheet = DeviceProfile.fromJson(Repo.text("shared_schemas/profiles/xiaomi-mi8-front.json"));
        Object[][] cases = {{measured, 3880, 5184}, {measured, 970, 1296}, {measured, 1080, 1920},
            {measured, 3000, 3000}, {datasheet, 970, 1296}, {datasheet, 1440, 1080}};
        JSONArray in = new JSONArray();
        for (Object[] c : cases) {
            in.put(new JSONObject().put("profile", ((DeviceProfile) c[0]).toJson()).put("width", c[1])
                    .put("height", c[2]));
        }
        Files.write(dir.resolve("profiles.json"), in.toString().getBytes(StandardCharsets.UTF_8));
        Python.run("camera/profile_intrinsics.py", dir.toString());
        JSONArray expected = new JSONArray(new String(Files.readAllBytes(dir.resolve("intrinsics.json")),
                StandardCharsets.UTF_8));
        for (int i = 0; i < cases.length; i++) {
            Intrinsics k = ((DeviceProfile) cases[i][0]).forFrame((Integer) cases[i][1], (Integer) cases[i][2]);
            JSONObject e = expected.getJSONObject(i);
            String what = "case " + i;
            assertEquals(e.getDouble("fx"), k.fx, 1e-9, what);
            assertEquals(e.getDouble("fy"), k.fy, 1e-9, what);
            assertEquals(e.getDouble("cx"), k.cx, 1e-9, what);
            assertEquals(e.getDouble("cy"), k.cy, 1e-9, what);
            assertEquals(e.getDouble("pixel_size_m"), k.pixelSizeM, 1e-18, what);
        }
        // The calibration's own size is the calibration itself.
        Intrinsics same = measured.forFrame(3880, 5184);
        assertEquals(1946.2, same.cx, 1e-9);
        assertArrayEquals(measured.distortion(), same.distortion(), 0.0);
    }

    @Test
    void writtenAndReadBack() throws Exception {
        DeviceProfile p = calibrated(1920, 1080);
        DeviceProfile back = DeviceProfile.fromJson(p.toJson().toString());
        assertEquals(p.toJson().toString(), back.toJson().toString());
        assertEquals(20, (int) back.intrinsics.views);
        assertNull(DeviceProfile.fromJson(Repo.text("shared_schemas/profiles/xiaomi-mi8-rear.json")).intrinsics);
    }

    @Test
    void badProfilesNameTheField() {
        JSONObject p = calibrated(1920, 1080).toJson();
        assertEquals("colour", assertThrows(ContractException.class,
                () -> DeviceProfile.fromJson(new JSONObject(p.toString()).put("colour", 1).toString())).field);
        assertEquals("facing", assertThrows(ContractException.class,
                () -> DeviceProfile.fromJson(new JSONObject(p.toString()).put("facing", "side").toString())).field);
        assertEquals("id", assertThrows(ContractException.class,
                () -> DeviceProfile.fromJson(new JSONObject(p.toString()).put("id", "a b").toString())).field);
        JSONObject k = new JSONObject(p.toString());
        k.getJSONObject("intrinsics").put("fx", 0.5);
        assertEquals("profile.intrinsics.fx", assertThrows(ContractException.class,
                () -> DeviceProfile.fromJson(k, "profile.")).field);
        assertEquals("distortion", assertThrows(ContractException.class, () -> DeviceProfile.fromJson(
                new JSONObject(p.toString()).put("distortion", new JSONArray("[1, 2, 3]")).toString())).field);
    }

    /** The phone's own profile for a calibration request, from a frame's camera at the output size. */
    @Test
    void aPhonesProfileFromItsFrames() {
        Intrinsics frame = new Intrinsics(1500, 1500, 999.5, 749.5, new double[] {0.01, 0, 0, 0, 0}, 3.2e-6, 4.8e-3,
                "x");
        DeviceProfile phone = DeviceProfile.ofPhone("Xiaomi MI 8 camera 0", "Xiaomi MI 8", LensFacing.BACK, frame, 2000,
                1500);
        assertEquals("Xiaomi-MI-8-camera-0", phone.id);
        assertEquals("rear", phone.facing);
        assertEquals(1500.0, phone.forFrame(2000, 1500).fx, 1e-9, "the datasheet pinhole is the frame's");
        assertThrows(IllegalArgumentException.class, () -> DeviceProfile.ofPhone("p", "p", LensFacing.FRONT,
                new Intrinsics(1500, 1500, 999.5, 749.5, null, null, null, null), 2000, 1500));
        assertEquals("phone", DeviceProfile.safeId("  "));
    }
}
