package io.lumipose.client.calibration;

import java.io.IOException;
import java.util.ArrayList;
import java.util.Collections;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Locale;
import java.util.Map;

import org.json.JSONObject;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.ServerRejectedException;

/**
 * The "Calibrate camera" screen's work (docs/android.md, "Calibrate camera"): each board photo goes
 * up once, whole, as a frame ({@code POST /v1/calibrations/views}, the board spec in
 * {@code X-Lumipose-Board}); the session keeps the small {@link BoardView}s the server returns and
 * the {@link BoardCoverage} of their corners; {@link #calibrate} posts the views as a
 * {@code CalibrationRequest} and stores an accepted profile ({@code PUT /v1/profiles/{id}}).
 *
 * <p>Photos may be added from one thread while the screen reads {@link #coverage()} on another;
 * the network calls hold no lock.
 */
public final class CalibrationSession {
    public static final String VIEWS_PATH = "/v1/calibrations/views";
    public static final String CALIBRATIONS_PATH = "/v1/calibrations";
    public static final String PROFILES_PATH = "/v1/profiles/";
    public static final String BOARD_HEADER = "X-Lumipose-Board";
    /** The schema of {@link #toJson}: the screen's saved session (the app's private storage, not the contract). */
    public static final String SCHEMA = "lumipose.calibration-session/1";
    /**
     * A printed board in room light, hand-held: 20 ms at ISO 800 (about what a phone's auto exposure
     * picks under 300-500 lux; the positioning frames' 10 ms at the lowest ISO would leave paper
     * black). The screen says when the picture is too dark or too bright ({@link #exposureHint}).
     */
    public static final long BOARD_EXPOSURE_NS = 20_000_000L;
    public static final int BOARD_ISO = 800;
    /** Mean grey levels outside which the board is hard to find. */
    static final double TOO_DARK_DN = 40;
    static final double TOO_BRIGHT_DN = 200;
    /** The route's status for a photo without a board. */
    static final int NO_BOARD_STATUS = 422;

    private final LumiposeClient client;
    private final BoardSpec board;
    private final List<BoardView> views = new ArrayList<BoardView>();
    private int photos;
    private int width;
    private int height;
    /** The grid's shape: the default until a report gives the server's. */
    private int gridRows;
    private int gridColumns;

    public CalibrationSession(LumiposeClient client, BoardSpec board) {
        this.client = client;
        this.board = board;
    }

    /** One photo's outcome: the corners found, or why none were. */
    public static final class Photo {
        public final String name;
        /** Null when no board was found. */
        public final BoardView view;
        /** The server's reason when it found no board on the photo (its 422 answer); null otherwise. */
        public final String refusal;

        Photo(String name, BoardView view, String refusal) {
            this.name = name;
            this.view = view;
            this.refusal = refusal;
        }

        public boolean found() {
            return view != null;
        }
    }

    /** What {@link #calibrate} got: the report and whether its profile was stored on the server. */
    public static final class Outcome {
        public final CalibrationReport report;
        public final boolean stored;
        /** Why the accepted profile was not stored on the server (no API key, ...); null otherwise. */
        public final String storeError;

        Outcome(CalibrationReport report, boolean stored, String storeError) {
            this.report = report;
            this.stored = stored;
            this.storeError = storeError;
        }

        /**
         * The outcome as the screen shows it: passed or not and why, the RMS, coverage and tilt, the
         * calibrated pinhole and where the profile went, or a refused set's fit said as not trusted (for a
         * look at how far it is from the datasheet, never used for frames), the advice, the photos left out.
         */
        public String describe() {
            CalibrationReport r = report;
            StringBuilder b = new StringBuilder();
            b.append(r.ok ? "Calibrated" : "Not calibrated: " + r.message).append(String.format(Locale.US,
                    "%nRMS %s px, coverage %.0f %%, most tilted view %s deg", r.rmsPx == null ? "?"
                            : String.format(Locale.US, "%.3f", r.rmsPx), 100 * r.coverage,
                    r.maxTiltDeg == null ? "?" : String.format(Locale.US, "%.0f", r.maxTiltDeg)));
            if (r.ok) {
                DeviceProfile.MeasuredPinhole k = r.profile.intrinsics;
                if (k != null) {
                    b.append(String.format(Locale.US, "%nfx %.1f  fy %.1f  cx %.1f  cy %.1f px", k.fx, k.fy, k.cx,
                            k.cy));
                }
                b.append("\nProfile ").append(r.profile.id).append(stored ? " stored on the server"
                        : " kept on the phone only (" + storeError + ")").append("; frames use it from now on.");
            } else if (r.fitted != null) {
                CalibrationReport.Fitted k = r.fitted;
                b.append(String.format(Locale.US, "%nFitted, NOT TRUSTED (not used): fx %.1f  fy %.1f  cx %.1f  "
                        + "cy %.1f px at %dx%d, k1 %.3f", k.fx, k.fy, k.cx, k.cy, k.width, k.height,
                        k.distortion()[0]));
            }
            for (String a : r.advice) {
                b.append("\n- ").append(a);
            }
            for (String left : r.leftOut) {
                b.append("\nleft out: ").append(left);
            }
            return b.toString();
        }
    }

    /**
     * The board photos' capture plan: the positioning plan's geometry (output size, crop, focus,
     * processing: the same intrinsics) with the board's exposure ({@link CapturePlan#forStills}).
     */
    public static CapturePlan boardPlan(CapturePlan positioning, CameraFacts facts)
            throws UnsupportedCameraException {
        return positioning.forStills(facts, BOARD_EXPOSURE_NS, BOARD_ISO);
    }

    /** What to tell the user about the light from the picture's mean grey level; null when it is fine. */
    public static String exposureHint(double meanDn) {
        if (meanDn < TOO_DARK_DN) {
            return "too dark: more light on the board";
        }
        return meanDn > TOO_BRIGHT_DN ? "too bright: less light on the board, no glare" : null;
    }

    public BoardSpec board() {
        return board;
    }

    /**
     * The session as plain JSON, for the screen to keep across its recreation and the process's
     * death: the board, the photo count, the photos' size, the views kept (their corners: a few kB
     * each, never the photos) and the report's coverage grid once there is one.
     */
    public synchronized JSONObject toJson() {
        JSONObject o = new JSONObject();
        Json.put(o, "schema", SCHEMA);
        Json.put(o, "board", board.toJson());
        Json.put(o, "photos", photos);
        Json.put(o, "width", width);
        Json.put(o, "height", height);
        Json.put(o, "grid_rows", gridRows);
        Json.put(o, "grid_columns", gridColumns);
        Json.put(o, "views", BoardView.toJson(views));
        return o;
    }

    /**
     * The session {@link #toJson} wrote, going on with {@code client}: more photos, the calibration.
     *
     * @throws ContractException naming the field when the text is not such a session (damaged,
     *         another schema, a view of another size than the session's, more views than photos)
     */
    public static CalibrationSession fromJson(LumiposeClient client, String text) {
        JSONObject o = Json.parseObject(text, "calibration session");
        if (!SCHEMA.equals(Json.optString(o, "schema", "schema"))) {
            throw new ContractException("schema", "must be '" + SCHEMA + "'");
        }
        BoardSpec board;
        try {
            board = BoardSpec.fromJson(Json.requireObject(o, "board", "board").toString());
        } catch (ContractException e) {
            throw e.within("board.");
        } catch (IllegalArgumentException e) {
            throw new ContractException("board", e.getMessage());
        }
        CalibrationSession s = new CalibrationSession(client, board);
        s.photos = Json.requireInt(o, "photos", "photos");
        s.width = Json.requireInt(o, "width", "width");
        s.height = Json.requireInt(o, "height", "height");
        s.gridRows = Json.requireInt(o, "grid_rows", "grid_rows");
        s.gridColumns = Json.requireInt(o, "grid_columns", "grid_columns");
        if (s.width < 0 || s.height < 0 || (s.width == 0) != (s.height == 0)) {
            throw new ContractException("width", "the photos' size must be positive (or 0 x 0 before the first), got "
                    + s.width + "x" + s.height);
        }
        if (s.gridRows < 0 || s.gridColumns < 0 || (s.gridRows == 0) != (s.gridColumns == 0)) {
            throw new ContractException("grid_rows", "the coverage grid must be positive (or 0 x 0 before a report), "
                    + "got " + s.gridRows + "x" + s.gridColumns);
        }
        List<JSONObject> views = Json.optObjects(o, "views", "views");
        for (int i = 0; i < views.size(); i++) {
            BoardView v;
            try {
                v = BoardView.fromJson(views.get(i).toString());
            } catch (ContractException e) {
                throw e.within("views[" + i + "].");
            }
            if (v.width != s.width || v.height != s.height) {
                throw new ContractException("views[" + i + "].width", "a " + v.width + "x" + v.height
                        + " view in a session of " + s.width + "x" + s.height + " photos");
            }
            s.views.add(v);
        }
        if (s.photos < s.views.size()) {
            throw new ContractException("photos", s.photos + " photos counted but " + s.views.size() + " views kept");
        }
        return s;
    }

    /**
     * Sends one board photo (a whole frame, as the positioning frames are described) and keeps its
     * corners. A photo without a board is an outcome, not an error: the user shoots again.
     *
     * @throws IllegalArgumentException for a window instead of a whole photo, or a photo of another
     *         size than the session's first (the views must share one size)
     */
    public Photo addPhoto(byte[] luma, FrameMeta meta) throws IOException, ServerRejectedException,
            InterruptedException {
        if (meta.isWindow()) {
            throw new IllegalArgumentException("a board photo goes whole, got a window of " + meta.fullWidth() + "x"
                    + meta.fullHeight());
        }
        String name;
        synchronized (this) {
            if (width != 0 && (meta.width != width || meta.height != height)) {
                throw new IllegalArgumentException("photo " + meta.width + "x" + meta.height + " is not the session's "
                        + width + "x" + height + ": start a new calibration after changing the frame size");
            }
            photos++;
            name = "photo-" + photos;
        }
        Map<String, String> headers = new LinkedHashMap<String, String>();
        headers.put(BOARD_HEADER, Json.asciiOnly(board.toJson().toString()));
        BoardView view;
        try {
            view = BoardView.fromJson(client.postFrame(VIEWS_PATH + "?name=" + LumiposeClient.urlEncode(name),
                    headers, luma, meta));
        } catch (ServerRejectedException e) {
            if (e.status == NO_BOARD_STATUS) {
                return new Photo(name, null, e.getMessage());
            }
            throw e;
        }
        if (view.width != meta.width || view.height != meta.height) {
            throw new ContractException("width", "the server saw a " + view.width + "x" + view.height + " photo, sent "
                    + meta.width + "x" + meta.height);
        }
        synchronized (this) {
            width = meta.width;
            height = meta.height;
            views.add(view);
        }
        return new Photo(name, view, null);
    }

    /** Photos sent so far, with or without a board. */
    public synchronized int photos() {
        return photos;
    }

    /** The views kept so far. */
    public synchronized List<BoardView> views() {
        return Collections.unmodifiableList(new ArrayList<BoardView>(views));
    }

    /** The coverage of the views kept so far; null before the first. */
    public synchronized BoardCoverage coverage() {
        if (views.isEmpty()) {
            return null;
        }
        if (gridRows == 0) {
            BoardCoverage shape = BoardCoverage.forImage(width, height);
            return BoardCoverage.of(views, width, height, shape.rows, shape.columns);
        }
        return BoardCoverage.of(views, width, height, gridRows, gridColumns);
    }

    /** {@link #calibrate(Object, String)} with the phone's own datasheet profile. */
    public Outcome calibrate(DeviceProfile phone, String profileId) throws IOException, ServerRejectedException,
            InterruptedException {
        return calibrate((Object) phone.toJson(), profileId);
    }

    /** {@link #calibrate(Object, String)} with a profile the server knows, by id. */
    public Outcome calibrate(String deviceProfileId, String profileId) throws IOException, ServerRejectedException,
            InterruptedException {
        return calibrate((Object) deviceProfileId, profileId);
    }

    /**
     * Posts the views as a {@code CalibrationRequest}; when the report is ok, stores its profile on
     * the server. From then on the report's coverage grid is the session's.
     *
     * @param profileId the calibrated profile's id, or null for the server's {@code <device id>-calibrated}
     * @throws IllegalStateException before any view
     */
    private Outcome calibrate(Object device, String profileId) throws IOException, ServerRejectedException,
            InterruptedException {
        JSONObject request = new JSONObject();
        synchronized (this) {
            if (views.isEmpty()) {
                throw new IllegalStateException("no board photo yet: shoot the board first");
            }
            Json.put(request, "board", board.toJson());
            Json.put(request, "views", BoardView.toJson(views));
        }
        Json.put(request, "device", device);
        if (profileId != null) {
            Json.put(request, "profile_id", profileId);
        }
        CalibrationReport report = CalibrationReport.fromJson(client.sendJson("POST", CALIBRATIONS_PATH, request));
        int[][] cells = report.coverageCells();
        if (cells.length > 0 && cells[0].length > 0) {
            synchronized (this) {
                gridRows = cells.length;
                gridColumns = cells[0].length;
            }
        }
        if (!report.ok) {
            return new Outcome(report, false, null);
        }
        try {
            client.sendJson("PUT", PROFILES_PATH + LumiposeClient.urlEncode(report.profile.id),
                    report.profile.toJson());
            return new Outcome(report, true, null);
        } catch (ServerRejectedException e) {
            // The phone keeps the profile anyway: its frames carry the intrinsics themselves.
            return new Outcome(report, false, e.getMessage());
        }
    }
}
