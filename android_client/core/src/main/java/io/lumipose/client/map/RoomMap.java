package io.lumipose.client.map;

import java.util.ArrayList;
import java.util.Arrays;
import java.util.Collections;
import java.util.List;
import java.util.Map;
import java.util.TreeMap;
import java.util.TreeSet;

import org.json.JSONObject;

import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/** The contract's beacon map ({@code lumipose.map/1}). */
public final class RoomMap {
    public static final String SCHEMA = "lumipose.map/1";
    /** A beacon's size fields; which it gives depends on its shape. */
    private static final String[] SIZE_FIELDS = {"side_m", "width_m", "height_m", "diameter_m"};
    public final String name;
    public final List<Beacon> beacons;
    /**
     * Compass bearing (deg clockwise from north) of the map's +X axis, as a survey measured it; null
     * when the map does not say (the app then falls back to the bearing typed in its settings).
     */
    public final Double bearingDeg;

    public RoomMap(String name, List<Beacon> beacons) {
        this(name, beacons, null);
    }

    public RoomMap(String name, List<Beacon> beacons, Double bearingDeg) {
        this.name = name;
        this.beacons = Collections.unmodifiableList(new ArrayList<Beacon>(beacons));
        this.bearingDeg = bearingDeg;
    }

    /**
     * The bearing of +X that turns compass readings into headings: the map's own (measured), else
     * {@code typedDeg} (the settings' value, may be null: then frames carry no heading).
     */
    public Double bearingOr(Double typedDeg) {
        return bearingDeg != null ? bearingDeg : typedDeg;
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
            beacons.add(beacon(b, "beacons[" + i + "]", Json.requireInt(b, "id", p + "id"), centre,
                    yaw == null ? 0 : yaw));
        }
        String name = Json.optString(o, "name", "name");
        Double bearing = ContractRanges.ANGLE_DEG.check("bearing_deg", Json.optDouble(o, "bearing_deg", "bearing_deg"));
        return new RoomMap(name == null ? "" : name, beacons, bearing);
    }

    /**
     * The beacon's shape and sizes (docs/contract.md, "Panel shapes"): a rounded rectangle gives
     * side_m, or width_m and height_m; a circle diameter_m alone and no corner radius. Another
     * combination names the beacon ({@code path}), as the server does; a bad number names its field.
     */
    private static Beacon beacon(JSONObject b, String path, int id, double[] centre, double yaw) {
        String p = path + ".";
        String shape = Json.optString(b, "shape", p + "shape");
        if (shape == null) {
            shape = Beacon.ROUNDED_RECTANGLE;
        } else if (!Beacon.ROUNDED_RECTANGLE.equals(shape) && !Beacon.CIRCLE.equals(shape)) {
            throw new ContractException(p + "shape", "must be '" + Beacon.ROUNDED_RECTANGLE + "' or '"
                    + Beacon.CIRCLE + "', got '" + shape + "'");
        }
        Map<String, Double> sizes = new TreeMap<String, Double>();
        for (String field : SIZE_FIELDS) {
            Double size = ContractRanges.BEACON_SIZE_M.check(p + field, Json.optDouble(b, field, p + field));
            if (size != null) {
                sizes.put(field, size);
            }
        }
        Double radius = ContractRanges.CORNER_RADIUS_M.check(p + "corner_radius_m",
                Json.optDouble(b, "corner_radius_m", p + "corner_radius_m"));
        if (Beacon.CIRCLE.equals(shape)) {
            if (!sizes.keySet().equals(Collections.singleton("diameter_m"))) {
                throw new ContractException(path, "a circle has diameter_m and no other size, got " + sizes.keySet());
            }
            if (radius != null && radius != 0) {
                throw new ContractException(p + "corner_radius_m", "a circle has no corner_radius_m, got " + radius);
            }
            return Beacon.circle(id, centre, yaw, sizes.get("diameter_m"));
        }
        double width;
        double height;
        if (sizes.keySet().equals(Collections.singleton("side_m"))) {
            width = sizes.get("side_m");
            height = width;
        } else if (sizes.keySet().equals(new TreeSet<String>(Arrays.asList("width_m", "height_m")))) {
            width = sizes.get("width_m");
            height = sizes.get("height_m");
        } else {
            throw new ContractException(path, "a rounded rectangle has side_m, or width_m and height_m, got "
                    + sizes.keySet());
        }
        double r = radius == null ? 0 : radius;
        if (!(2 * r < Math.min(width, height))) {
            throw new ContractException(p + "corner_radius_m", "must be less than half of the panel's shorter side "
                    + Math.min(width, height) + ", got " + r);
        }
        return Beacon.roundedRectangle(id, centre, yaw, width, height, r);
    }
}
