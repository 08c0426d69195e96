package io.lumipose.client.survey;

import java.io.IOException;
import java.util.ArrayList;
import java.util.Collections;
import java.util.List;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.contract.ContractRanges;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.ServerRejectedException;
import io.lumipose.client.net.StoredSample;

/**
 * The "Survey room" screen's work (docs/android.md, "Survey room"): photos of the ceiling taken from
 * the floor, each seeing two or more panels, go up whole as stored samples ({@code POST /v1/samples}
 * with a label naming the survey and the photo); the user names the panels on each photo
 * ({@link #label}: a beacon ID and a pixel inside its image, the contract's {@code PanelLabel});
 * {@link #survey} posts the {@code SurveyRequest} (the active map as the sketch, the anchor the user
 * chose, store true) and {@link #activate} makes the surveyed map the server's active one.
 *
 * <p>Photos may be added on one thread while the screen reads {@link #shots()} on another; the
 * network calls hold no lock.
 */
public final class SurveySession {
    public static final String SURVEYS_PATH = "/v1/surveys";
    /** The schema of {@link #toJson}: the screen's saved session (the app's private storage, not the contract). */
    public static final String SCHEMA = "lumipose.survey-session/1";

    /** A panel named on a photo: the contract's {@code PanelLabel}. */
    public static final class Label {
        public final int beaconId;
        public final double xPx;
        public final double yPx;

        public Label(int beaconId, double xPx, double yPx) {
            if (beaconId < 0 || beaconId > 255) {
                throw new IllegalArgumentException("beacon ID must be within [0, 255], got " + beaconId);
            }
            if (!(xPx >= 0) || !(yPx >= 0)) {
                throw new IllegalArgumentException("a label's pixel must be >= 0, got (" + xPx + ", " + yPx + ")");
            }
            this.beaconId = beaconId;
            this.xPx = xPx;
            this.yPx = yPx;
        }

        JSONObject toJson() {
            JSONObject o = new JSONObject();
            Json.put(o, "beacon_id", beaconId);
            Json.put(o, "x_px", xPx);
            Json.put(o, "y_px", yPx);
            return o;
        }
    }

    /** One stored photo and the panels named on it. */
    public static final class Shot {
        public final String sampleId;
        public final int width;
        public final int height;
        /** What the server said when it stored the photo (a fix in the sketch, or why none). */
        public final LocateResult stored;
        public final List<Label> labels;

        Shot(String sampleId, int width, int height, LocateResult stored, List<Label> labels) {
            this.sampleId = sampleId;
            this.width = width;
            this.height = height;
            this.stored = stored;
            this.labels = Collections.unmodifiableList(new ArrayList<Label>(labels));
        }

        Shot withLabel(Label l) {
            List<Label> more = new ArrayList<Label>(labels);
            more.add(l);
            return new Shot(sampleId, width, height, stored, more);
        }
    }

    private final LumiposeClient client;
    private final String name;
    private final List<Shot> shots = new ArrayList<Shot>();
    private int photos;

    /**
     * @param name the surveyed map's name (the service's map names); the photos are stored with the
     *             labels {@code survey:<name>:<n>}
     */
    public SurveySession(LumiposeClient client, String name) {
        this.client = client;
        this.name = ContractRanges.checkName("name", name);
    }

    public String name() {
        return name;
    }

    /**
     * The session as plain JSON, for the screen to keep across its recreation and the process's
     * death: the name, the photo count (the next sample's label number), every stored photo's
     * sample id, size, stored result and labels. Not the photos themselves: they are on the server.
     */
    public synchronized JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "schema", SCHEMA);
        Json.put(o, "name", name);
        Json.put(o, "photos", photos);
        JSONArray a = new JSONArray();
        for (Shot shot : shots) {
            JSONObject j = new JSONObject();
            Json.put(j, "sample_id", shot.sampleId);
            Json.put(j, "width", shot.width);
            Json.put(j, "height", shot.height);
            Json.put(j, "stored", shot.stored.toJson());
            JSONArray labels = new JSONArray();
            for (Label l : shot.labels) {
                labels.put(l.toJson());
            }
            Json.put(j, "labels", labels);
            a.put(j);
        }
        Json.put(o, "shots", a);
        return o;
    }

    /**
     * The session {@link #toJson} wrote, going on with {@code client}: more photos, labels, the survey.
     *
     * @throws ContractException naming the field when the text is not such a session (damaged,
     *         another schema, a label outside its photo, fewer photos counted than stored)
     */
    public static SurveySession fromJson(LumiposeClient client, String text) {
        JSONObject o = Json.parseObject(text, "survey session");
        if (!SCHEMA.equals(Json.optString(o, "schema", "schema"))) {
            throw new ContractException("schema", "must be '" + SCHEMA + "'");
        }
        String name = Json.optString(o, "name", "name");
        if (name == null) {
            throw new ContractException("name", "missing");
        }
        SurveySession s;
        try {
            s = new SurveySession(client, name);
        } catch (IllegalArgumentException e) {
            throw new ContractException("name", e.getMessage());
        }
        List<JSONObject> shots = Json.optObjects(o, "shots", "shots");
        int photos = Json.requireInt(o, "photos", "photos");
        if (photos < shots.size()) {
            throw new ContractException("photos", photos + " photos counted but " + shots.size() + " stored");
        }
        s.photos = photos;
        for (int i = 0; i < shots.size(); i++) {
            String path = "shots[" + i + "]";
            JSONObject j = shots.get(i);
            String sampleId = Json.optString(j, "sample_id", path + ".sample_id");
            if (sampleId == null || sampleId.isEmpty()) {
                throw new ContractException(path + ".sample_id", "missing");
            }
            int width = Json.requireInt(j, "width", path + ".width");
            int height = Json.requireInt(j, "height", path + ".height");
            if (width <= 0 || height <= 0) {
                throw new ContractException(path + ".width", "the photo's size must be positive, got " + width
                        + "x" + height);
            }
            LocateResult stored;
            try {
                stored = LocateResult.fromJson(Json.requireObject(j, "stored", path + ".stored"));
            } catch (ContractException e) {
                throw e.field.startsWith(path) ? e : e.within(path + ".stored.");
            }
            s.shots.add(new Shot(sampleId, width, height, stored, Collections.<Label>emptyList()));
            List<JSONObject> labels = Json.optObjects(j, "labels", path + ".labels");
            for (int k = 0; k < labels.size(); k++) {
                String lp = path + ".labels[" + k + "]";
                JSONObject l = labels.get(k);
                try {
                    s.label(i, Json.requireInt(l, "beacon_id", lp + ".beacon_id"),
                            Json.requireDouble(l, "x_px", lp + ".x_px"), Json.requireDouble(l, "y_px", lp + ".y_px"));
                } catch (ContractException e) {
                    throw e;
                } catch (IllegalArgumentException e) {
                    throw new ContractException(lp, e.getMessage());
                }
            }
        }
        return s;
    }

    /**
     * Stores one photo as a sample (sent once: a retry would store it twice).
     *
     * @throws IllegalArgumentException for a window: a survey photo must show every panel in view
     */
    public Shot addPhoto(byte[] luma, FrameMeta meta) throws IOException, ServerRejectedException,
            InterruptedException {
        if (meta.isWindow()) {
            throw new IllegalArgumentException("a survey photo goes whole (it must show two or more panels), got a "
                    + "window");
        }
        int n;
        synchronized (this) {
            n = ++photos;
        }
        StoredSample s = client.storeSample("survey:" + name + ":" + n, luma, meta);
        Shot shot = new Shot(s.id, meta.width, meta.height, s.result, Collections.<Label>emptyList());
        synchronized (this) {
            shots.add(shot);
        }
        return shot;
    }

    /**
     * Names a panel on photo {@code index}: {@code beaconId} is the panel whose image holds the pixel.
     *
     * @throws IllegalArgumentException naming what is wrong (no such photo, a pixel outside it)
     */
    public synchronized Shot label(int index, int beaconId, double xPx, double yPx) {
        if (index < 0 || index >= shots.size()) {
            throw new IllegalArgumentException("no photo " + index + " (" + shots.size() + " taken)");
        }
        Shot shot = shots.get(index);
        if (xPx > shot.width - 1 || yPx > shot.height - 1) {
            throw new IllegalArgumentException("pixel (" + xPx + ", " + yPx + ") outside the " + shot.width + "x"
                    + shot.height + " photo");
        }
        Shot labelled = shot.withLabel(new Label(beaconId, xPx, yPx));
        shots.set(index, labelled);
        return labelled;
    }

    /** The photos so far, in order. */
    public synchronized List<Shot> shots() {
        return Collections.unmodifiableList(new ArrayList<Shot>(shots));
    }

    /**
     * Posts the survey of every photo so far; the surveyed map is stored under the session's name.
     *
     * @param sketch the stored map that names the room's panels (the screen's active map)
     * @param anchor the panel whose sketch position and yaw fix the map's frame
     * @throws ServerRejectedException when the server refuses the set (a panel unconnected to the
     *         anchor, named in the message)
     * @throws IOException without an answer: sent once, so the map may be stored all the same
     * @throws IllegalStateException before any photo
     */
    public SurveyReport survey(String sketch, int anchor) throws IOException, ServerRejectedException,
            InterruptedException {
        ContractRanges.checkName("sketch", sketch);
        if (anchor < 0 || anchor > 255) {
            throw new IllegalArgumentException("anchor must be a beacon ID within [0, 255], got " + anchor);
        }
        JSONArray samples = new JSONArray();
        synchronized (this) {
            if (shots.isEmpty()) {
                throw new IllegalStateException("no photo yet: photograph the ceiling first");
            }
            for (Shot s : shots) {
                JSONObject sample = new JSONObject();
                Json.put(sample, "sample_id", s.sampleId);
                JSONArray labels = new JSONArray();
                for (Label l : s.labels) {
                    labels.put(l.toJson());
                }
                Json.put(sample, "labels", labels);
                samples.put(sample);
            }
        }
        JSONObject request = new JSONObject();
        Json.put(request, "name", name);
        Json.put(request, "sketch", sketch);
        Json.put(request, "anchor", anchor);
        Json.put(request, "samples", samples);
        Json.put(request, "store", Boolean.TRUE);
        // once, with a long wait: a survey of many photos runs for minutes, and stores the map
        return SurveyReport.fromJson(client.postJsonOnce(SURVEYS_PATH, request));
    }

    /**
     * Makes the surveyed map the server's active map ({@code PUT /v1/maps/active}).
     *
     * @throws IllegalStateException when the report says the map was not stored
     */
    public void activate(SurveyReport report) throws IOException, ServerRejectedException, InterruptedException {
        if (!report.stored) {
            throw new IllegalStateException("map '" + report.map.name + "' was not stored: it cannot become active");
        }
        client.setActiveMap(report.map.name);
    }
}
