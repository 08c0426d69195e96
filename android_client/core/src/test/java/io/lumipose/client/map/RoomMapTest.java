package io.lumipose.client.map;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.assertNull;
import static org.junit.jupiter.api.Assertions.assertThrows;

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
}
