package io.lumipose.client.survey;

import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONObject;

import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;
import io.lumipose.client.map.RoomMap;

/**
 * The contract's {@code SurveyReport} ({@code lumipose.survey-report/1}): the surveyed map, every
 * panel's position and yaw with its 1-sigma, the frames used and those left out with the reason,
 * and the map's compass bearing when the frames carried compass readings.
 */
public final class SurveyReport {
    public static final String SCHEMA = "lumipose.survey-report/1";

    /** One panel as the survey placed it. */
    public static final class SurveyedBeacon {
        public final int beaconId;
        private final double[] centerM;
        public final double yawDeg;
        private final double[] centerSigmaM;
        public final double yawSigmaDeg;
        public final int frames;

        SurveyedBeacon(int beaconId, double[] centerM, double yawDeg, double[] centerSigmaM, double yawSigmaDeg,
                       int frames) {
            this.beaconId = beaconId;
            this.centerM = centerM.clone();
            this.yawDeg = yawDeg;
            this.centerSigmaM = centerSigmaM.clone();
            this.yawSigmaDeg = yawSigmaDeg;
            this.frames = frames;
        }

        public double[] centerM() {
            return centerM.clone();
        }

        public double[] centerSigmaM() {
            return centerSigmaM.clone();
        }
    }

    /** A frame the fit left out. */
    public static final class Skipped {
        public final String name;
        public final String why;

        Skipped(String name, String why) {
            this.name = name;
            this.why = why;
        }
    }

    public final RoomMap map;
    public final List<SurveyedBeacon> beacons;
    public final int framesUsed;
    public final List<Skipped> skipped;
    public final double rmsPx;
    public final Double bearingDeg;
    public final Double bearingSigmaDeg;
    public final boolean stored;

    private SurveyReport(RoomMap map, List<SurveyedBeacon> beacons, int framesUsed, List<Skipped> skipped,
                         double rmsPx, Double bearingDeg, Double bearingSigmaDeg, boolean stored) {
        this.map = map;
        this.beacons = Collections.unmodifiableList(beacons);
        this.framesUsed = framesUsed;
        this.skipped = Collections.unmodifiableList(skipped);
        this.rmsPx = rmsPx;
        this.bearingDeg = bearingDeg;
        this.bearingSigmaDeg = bearingSigmaDeg;
        this.stored = stored;
    }

    public static SurveyReport fromJson(String text) {
        JSONObject o = Json.parseObject(text, "survey report");
        Json.checkSchema(o, SCHEMA);
        RoomMap map;
        try {
            map = RoomMap.fromJson(Json.requireObject(o, "map", "map").toString());
        } catch (ContractException e) {
            throw e.within("map.");
        }
        List<SurveyedBeacon> beacons = new ArrayList<SurveyedBeacon>();
        List<JSONObject> items = Json.optObjects(o, "beacons", "beacons");
        for (int i = 0; i < items.size(); i++) {
            JSONObject b = items.get(i);
            String p = "beacons[" + i + "].";
            double[] centre = Json.optDoubles(b, "center_m", p + "center_m", 3);
            double[] sigma = Json.optDoubles(b, "center_sigma_m", p + "center_sigma_m", 3);
            if (centre == null || sigma == null) {
                throw new ContractException(p + (centre == null ? "center_m" : "center_sigma_m"), "missing");
            }
            beacons.add(new SurveyedBeacon(Json.requireInt(b, "beacon_id", p + "beacon_id"), centre,
                    Json.requireDouble(b, "yaw_deg", p + "yaw_deg"), sigma,
                    Json.requireDouble(b, "yaw_sigma_deg", p + "yaw_sigma_deg"),
                    Json.requireInt(b, "frames", p + "frames")));
        }
        List<Skipped> skipped = new ArrayList<Skipped>();
        List<JSONObject> left = Json.optObjects(o, "skipped", "skipped");
        for (int i = 0; i < left.size(); i++) {
            skipped.add(new Skipped(Json.optString(left.get(i), "name", "skipped[" + i + "].name"),
                    Json.optString(left.get(i), "why", "skipped[" + i + "].why")));
        }
        Boolean stored = Json.optBoolean(o, "stored", "stored");
        return new SurveyReport(map, beacons, Json.requireInt(o, "frames_used", "frames_used"), skipped,
                Json.requireDouble(o, "rms_px", "rms_px"), Json.optDouble(o, "bearing_deg", "bearing_deg"),
                Json.optDouble(o, "bearing_sigma_deg", "bearing_sigma_deg"), stored != null && stored);
    }
}
