package io.lumipose.client.map;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertFalse;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;
import static org.junit.jupiter.api.Assertions.assertTrue;

import org.junit.jupiter.api.Test;

import io.lumipose.client.json.ContractException;

class RoomMapTest {
    @Test
    void cornersFollowTheYaw() {
        Beacon b = new Beacon(1, new double[] {1, 2, 3}, 0, 0.2);
        assertEquals(0.9, b.cornersXyM()[0][0], 1e-12);
        assertEquals(1.9, b.cornersXyM()[0][1], 1e-12);
        Beacon turned = new Beacon(1, new double[] {0, 0, 3}, 45, 0.2);
        // At 45 deg the first corner lies on -Y at half the diagonal.
        assertEquals(0.0, turned.cornersXyM()[0][0], 1e-12);
        assertEquals(-0.1 * Math.sqrt(2), turned.cornersXyM()[0][1], 1e-12);
    }

    @Test
    void badMapsNameTheField() {
        assertEquals("beacons[0].side_m", assertThrows(ContractException.class, () -> RoomMap.fromJson(
                "{\"beacons\": [{\"id\": 1, \"center_m\": [0, 0, 1], \"side_m\": -1}]}")).field);
        assertEquals("beacons[0].center_m", assertThrows(ContractException.class, () -> RoomMap.fromJson(
                "{\"beacons\": [{\"id\": 1, \"center_m\": [0, 0], \"side_m\": 1}]}")).field);
        assertEquals("beacons", assertThrows(ContractException.class, () -> RoomMap.fromJson("{\"beacons\": []}"))
                .field);
        assertEquals("map", assertThrows(ContractException.class, () -> RoomMap.fromJson("not json")).field);
        assertNull(RoomMap.fromJson("{\"beacons\": [{\"id\": 1, \"center_m\": [0, 0, 1], \"side_m\": 1}]}")
                .beacon(2));
    }

    /** A surveyed map's bearing wins over the typed one; without one the typed one (or none) is used. */
    @Test
    void theMapsBearingWinsOverTheTypedOne() {
        String beacons = "\"beacons\": [{\"id\": 1, \"center_m\": [0, 0, 1], \"side_m\": 1}]";
        RoomMap surveyed = RoomMap.fromJson("{" + beacons + ", \"bearing_deg\": 12.5}");
        assertEquals(12.5, surveyed.bearingDeg, 0.0);
        assertEquals(12.5, surveyed.bearingOr(90.0), 0.0);
        RoomMap sketch = RoomMap.fromJson("{" + beacons + "}");
        assertNull(sketch.bearingDeg);
        assertEquals(90.0, sketch.bearingOr(90.0), 0.0);
        assertNull(sketch.bearingOr(null));
        assertEquals("bearing_deg", assertThrows(ContractException.class, () -> RoomMap.fromJson("{" + beacons
                + ", \"bearing_deg\": \"north\"}")).field);
    }

    private static Beacon only(String beacon) {
        return RoomMap.fromJson("{\"beacons\": [{\"id\": 1, \"center_m\": [0, 0, 1], " + beacon + "}]}").beacon(1);
    }

    private static ContractException refused(String beacon) {
        return assertThrows(ContractException.class, () -> only(beacon));
    }

    @Test
    void aSquareIsTheDefaultShape() {
        Beacon b = only("\"side_m\": 0.174, \"corner_radius_m\": 0.02");
        assertEquals(Beacon.ROUNDED_RECTANGLE, b.shape);
        assertEquals(0.174, b.widthM, 0);
        assertEquals(0.174, b.heightM, 0);
        assertEquals(0.02, b.cornerRadiusM, 0);
        assertTrue(b.hasCorners());
    }

    @Test
    void aRectangleHasItsWidthAlongXbAndItsHeightAlongYb() {
        Beacon b = only("\"shape\": \"rounded_rectangle\", \"width_m\": 1.2, \"height_m\": 0.3, \"yaw_deg\": 90");
        assertEquals(1.2, b.widthM, 0);
        assertEquals(0.3, b.heightM, 0);
        assertEquals(1.2, b.sizeM(), 0);
        // At yaw 90 the width runs along the map's Y: the corners span 0.3 m in X and 1.2 m in Y.
        double[][] c = b.cornersXyM();
        assertEquals(0.15, c[0][0], 1e-12);
        assertEquals(-0.6, c[0][1], 1e-12);
        assertEquals(0.3, only("\"width_m\": 0.3, \"height_m\": 0.6").widthM, 0); // the shape may be left out
    }

    @Test
    void aCircleHasItsDiameterOnly() {
        Beacon b = only("\"shape\": \"circle\", \"diameter_m\": 0.2");
        assertTrue(b.isCircle());
        assertFalse(b.hasCorners());
        assertEquals(0.2, b.widthM, 0);
        assertEquals(0.2, b.heightM, 0);
        assertEquals(0, b.cornerRadiusM, 0);
        assertEquals(0.1, b.outlineRadiusM(), 0);
        assertTrue(only("\"shape\": \"circle\", \"diameter_m\": 0.2, \"corner_radius_m\": 0").isCircle());
        assertTrue(only("\"shape\": \"circle\", \"diameter_m\": 0.2, \"side_m\": null").isCircle(),
                "an optional field may be null");
    }

    @Test
    void otherSizesAreRefusedNamingTheBeaconAndTheFields() {
        ContractException mixed = refused("\"side_m\": 0.2, \"width_m\": 0.3");
        assertEquals("beacons[0]", mixed.field);
        assertTrue(mixed.getMessage().contains("a rounded rectangle has side_m, or width_m and height_m, got "
                + "[side_m, width_m]"), mixed.getMessage());
        assertEquals("beacons[0]", refused("\"width_m\": 0.3").field);
        assertEquals("beacons[0]", refused("\"corner_radius_m\": 0.01").field);
        assertEquals("beacons[0]", refused("\"diameter_m\": 0.2").field);
        ContractException circle = refused("\"shape\": \"circle\", \"diameter_m\": 0.2, \"side_m\": 0.2");
        assertEquals("beacons[0]", circle.field);
        assertTrue(circle.getMessage().contains("a circle has diameter_m and no other size, got [diameter_m, side_m]"),
                circle.getMessage());
        assertEquals("beacons[0]", refused("\"shape\": \"circle\", \"side_m\": 0.2").field);
    }

    @Test
    void aCircleWithACornerRadiusAndAnUnknownShapeAreRefused() {
        ContractException radius = refused("\"shape\": \"circle\", \"diameter_m\": 0.2, \"corner_radius_m\": 0.02");
        assertEquals("beacons[0].corner_radius_m", radius.field);
        assertTrue(radius.getMessage().contains("a circle has no corner_radius_m"), radius.getMessage());
        assertEquals("beacons[0].shape", refused("\"shape\": \"hexagon\", \"side_m\": 0.2").field);
        assertEquals("beacons[0].corner_radius_m",
                refused("\"width_m\": 1.2, \"height_m\": 0.3, \"corner_radius_m\": 0.15").field);
        only("\"width_m\": 1.2, \"height_m\": 0.3, \"corner_radius_m\": 0.149");
    }

    @Test
    void theOutlineIsTheRoundedShapeInTheFloorPlane() {
        Beacon circle = Beacon.circle(1, new double[] {1, 2, 3}, 30, 0.2);
        double[][] round = circle.outlineXyM(16);
        assertEquals(64, round.length);
        for (double[] q : round) {
            assertEquals(0.1, Math.hypot(q[0] - 1, q[1] - 2), 1e-12);
        }
        Beacon sharp = new Beacon(1, new double[] {0, 0, 3}, 0, 0.2);
        assertEquals(4, sharp.outlineXyM(16).length, "sharp corners: one point each");
        Beacon rounded = Beacon.roundedRectangle(1, new double[] {0, 0, 3}, 0, 1.2, 0.3, 0.05);
        double maxX = 0;
        double maxY = 0;
        for (double[] q : rounded.outlineXyM(8)) {
            maxX = Math.max(maxX, Math.abs(q[0]));
            maxY = Math.max(maxY, Math.abs(q[1]));
            // Every point is on a corner arc: 0.05 m from the nearest arc centre (+-0.55, +-0.1).
            assertEquals(0.05, Math.hypot(Math.abs(q[0]) - 0.55, Math.abs(q[1]) - 0.1), 1e-12);
        }
        assertEquals(0.6, maxX, 1e-12);
        assertEquals(0.15, maxY, 1e-12);
    }
}
