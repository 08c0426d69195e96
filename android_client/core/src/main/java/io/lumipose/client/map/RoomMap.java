package io.lumipose.client.map;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The contract's beacon map ({@code lumipose.map/1}). */
public final class RoomMap {
    public static final String SCHEMA = "lumipose.map/1";
    public final String name;
    public final List<Beacon> beacons;

    public RoomMap(String name, List<Beacon> beacons) {
        this.name = name;
        this.beacons = Collections.unmodifiableList(new ArrayList<Beacon>(beacons));
    }

    public Beacon beacon(int id) {
        for (Beacon b : beacons) {
            if (b.id == id) {
                return b;
            }
        }
        return null;
    }

    public static RoomMap fromJson(String text) {
        JSONObject o = Json.parseObject(text, "map");
        Json.checkSchema(o, SCHEMA);
        List<Beacon> beacons = new ArrayList<Beacon>();
        List<JSONObject> items = Json.optObjects(o, "beacons", "beacons");
        if (items.isEmpty()) {
            throw new ContractException("beacons", "a map needs at least one beacon");
        }
        for (int i = 0; i < items.size(); i++) {
            JSONObject b = items.get(i);
            String p = "beacons[" + i + "].";
            double[] centre = Json.optDoubles(b, "center_m", p + "center_m", 3);
            if (centre == null) {
                throw new ContractException(p + "center_m", "missing");
            }
            ContractRanges.COORDINATE_M.checkEach(p + "center_m", centre);
            Double yaw = ContractRanges.ANGLE_DEG.check(p + "yaw_deg", Json.optDouble(b, "yaw_deg", p + "yaw_deg"));
            double side = ContractRanges.BEACON_SIDE_M.check(p + "side_m", Json.requireDouble(b, "side_m", p + "side_m"));
            ContractRanges.CORNER_RADIUS_M.check(p + "corner_radius_m",
                    Json.optDouble(b, "corner_radius_m", p + "corner_radius_m"));
            beacons.add(new Beacon(Json.requireInt(b, "id", p + "id"), centre, yaw == null ? 0 : yaw, side));
        }
        String name = Json.optString(o, "name", "name");
        return new RoomMap(name == null ? "" : name, beacons);
    }
}
