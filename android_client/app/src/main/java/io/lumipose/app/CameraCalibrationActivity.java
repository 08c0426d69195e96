package io.lumipose.app;

import android.graphics.Canvas;
import android.graphics.Color;
import android.graphics.Paint;
import android.os.Build;
import android.os.Bundle;
import android.widget.Button;
import android.widget.EditText;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.io.IOException;
import java.util.Locale;

import org.json.JSONObject;

import io.lumipose.client.calibration.BoardCoverage;
import io.lumipose.client.calibration.BoardSpec;
import io.lumipose.client.calibration.CalibrationSession;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.DeviceProfile;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.GreyPreview;
import io.lumipose.client.json.Json;

/**
 * "Calibrate camera": photographs the calibration board (ChArUco or chessboard, {@code BoardSpec}) with
 * the positioning frames' geometry (output size, crop, focus, processing) at the board's exposure,
 * sends each photo once to POST /v1/calibrations/views, shows which cells of the image the corners have covered, then posts
 * the views (POST /v1/calibrations) and shows the report. An accepted profile is stored on the
 * server (PUT /v1/profiles/{id}) and on the phone: from then on every frame of this camera carries
 * its intrinsics (docs/android.md, "Calibrate camera"). The core's CalibrationSession does the work.
 */
public final class CameraCalibrationActivity extends StillActivity {
    /** The session's file in the app's private storage (docs/android.md, "Sessions across recreation"). */
    static final String SESSION_FILE = "calibration-session.json";
    private static final String SCHEMA = "lumipose.app.calibration-screen/1";
    private static final int ID_BOARD = 1;
    private final Paint empty = new Paint();
    private final Paint covered = new Paint();
    private final Paint grid = new Paint();
    private EditText boardField;
    private TextView counts;
    private TextView report;
    private Button calibrate;
    /** The calibration and its file: made on the first photo, restored, finished, started over on the UI thread. */
    private ScreenSession<CalibrationSession> sessions;
    /** Kept beside the session: changed with it (under {@link ScreenSession#ifCurrent}) or cleared after it. */
    private volatile FrameMeta firstPhoto;
    private volatile BoardCoverage coverage;

    @Override
    protected void buildViews() {
        empty.setColor(Color.argb(70, 255, 0, 0));
        covered.setColor(Color.argb(70, 0, 200, 0));
        grid.setColor(Color.YELLOW);
        grid.setStyle(Paint.Style.STROKE);
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        root.setPadding(16, 16, 16, 16);
        TextView intro = new TextView(this);
        intro.setText("Photograph the printed board at the distance of the ceiling, tilted, filling every cell of "
                + "the grid (red: too few corners yet). Board spec (the board.json printed with it, or the spec of a "
                + "board you own):");
        boardField = new EditText(this);
        boardField.setId(ID_BOARD);
        boardField.setText(prefs.boardSpecJson());
        counts = new TextView(this);
        report = new TextView(this);
        root.addView(intro);
        root.addView(boardField);
        calibrate = addCameraViews(root, new PreviewView.Overlay() {
            @Override
            public void draw(Canvas canvas, GreyPreview p) {
                drawCoverage(canvas, p);
            }
        }, "Calibrate", new Runnable() {
            @Override
            public void run() {
                calibrate();
            }
        });
        Forms.button(this, root, "Start over", new Runnable() {
            @Override
            public void run() {
                startOver();
            }
        });
        root.addView(counts);
        root.addView(report);
        root.addView(status);
        setContentView(root);
    }

    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        sessions = new ScreenSession<CalibrationSession>(this, SESSION_FILE,
                new ScreenSession.Encoder<CalibrationSession>() {
                    @Override
                    public String json(CalibrationSession s) {
                        return screenJson(s);
                    }
                }, new SessionFile.Failure() {
                    @Override
                    public void failed(IOException e) {
                        showStatus("The calibration could not be saved on the phone: " + e.getMessage());
                    }
                });
        restore();
    }

    @Override
    protected void onDestroy() {
        sessions.leave();
        super.onDestroy();
    }

    /**
     * The session saved before the screen was recreated or the process died (its views, coverage and
     * first photo's description); a file that cannot be read is said, dropped, and a new one starts.
     */
    private void restore() {
        CalibrationSession s;
        FrameMeta first = null;
        try {
            String text = sessions.saved();
            if (text == null) {
                return;
            }
            JSONObject o = Json.parseObject(text, "calibration screen");
            if (!SCHEMA.equals(Json.optString(o, "schema", "schema"))) {
                throw new IllegalArgumentException("schema: must be '" + SCHEMA + "'");
            }
            s = CalibrationSession.fromJson(client, Json.requireObject(o, "session", "session").toString());
            JSONObject meta = Json.optObject(o, "first_photo", "first_photo");
            if (meta != null) {
                first = FrameMeta.fromJson(meta.toString());
            }
            if ((first == null) != s.views().isEmpty()) {
                throw new IllegalArgumentException("first_photo: " + (first == null ? "missing" : "without a view"));
            }
        } catch (IOException | IllegalArgumentException e) {
            sessions.discardSaved();
            report.setText("The calibration saved on the phone could not be restored (" + e.getMessage()
                    + "): a new one starts.");
            return;
        }
        firstPhoto = first;
        sessions.adopt(s, false);
        coverage = s.coverage();
        boardField.setText(s.board().toJson().toString());
        boardField.setEnabled(false);
        calibrate.setEnabled(first != null);
        counts.setText(photoCounts());
        report.setText("Calibration restored: " + s.views().size() + " board views kept. Go on shooting, or tap "
                + "Calibrate.");
    }

    /** The session's file: the session and the first photo's description (whose camera the profile takes). */
    private String screenJson(CalibrationSession s) {
        JSONObject o = new JSONObject();
        Json.put(o, "schema", SCHEMA);
        Json.put(o, "session", s.toJson());
        FrameMeta first = firstPhoto;
        if (first != null) {
            Json.put(o, "first_photo", first.toJson());
        }
        return o.toString();
    }

    /** UI thread: forgets the session and its file. */
    private void dropSession() {
        sessions.forget();
        firstPhoto = null; // after: no upload of the forgotten session sets them again
        coverage = null;
        boardField.setEnabled(true);
        calibrate.setEnabled(false);
        counts.setText(photoCounts());
        preview.invalidate();
    }

    private void startOver() {
        dropSession();
        report.setText("Started over: a new calibration.");
    }

    /** The board's exposure on the positioning plan's geometry, so the photos share its intrinsics. */
    @Override
    public CapturePlan plan(CameraFacts facts, CapturePlan positioning) throws UnsupportedCameraException {
        return CalibrationSession.boardPlan(positioning, facts);
    }

    /** Board photos carry Camera2's intrinsics: the phone's datasheet profile is made from them. */
    @Override
    protected FrameDescriber describer(CameraFacts facts, CapturePlan plan) {
        return new FrameDescriber(facts, plan, mapBearingDeg(), null);
    }

    @Override
    protected void onShutter() {
        if (sessions.current() == null) {
            try {
                BoardSpec board = prefs.saveBoardSpec(boardField.getText().toString());
                CalibrationSession s = new CalibrationSession(client, board);
                boardField.setEnabled(false);
                sessions.adopt(s, true);
            } catch (IllegalArgumentException e) {
                report.setText("Board spec: " + e.getMessage());
                return;
            }
        }
        takePhoto();
    }

    @Override
    protected void onPreviewShown(GreyPreview p) {
        super.onPreviewShown(p);
        String hint = CalibrationSession.exposureHint(p.meanDn());
        counts.setText(photoCounts() + (hint == null ? "" : "\nLight: " + hint));
    }

    private String photoCounts() {
        CalibrationSession s = sessions.current();
        BoardCoverage c = coverage;
        if (s == null) {
            return "No photo yet.";
        }
        return String.format(Locale.US, "%d photos, %d with the board; %.0f %% of the cells covered", s.photos(),
                s.views().size(), c == null ? 0.0 : 100 * c.coverage());
    }

    @Override
    protected void handlePhoto(byte[] luma, final FrameMeta meta) {
        final CalibrationSession s = sessions.current();
        if (s == null) {
            shutterBack(null);
            return;
        }
        String outcome;
        try {
            CalibrationSession.Photo photo = s.addPhoto(luma, meta);
            if (photo.found()) {
                sessions.ifCurrent(s, new Runnable() {
                    @Override
                    public void run() {
                        if (firstPhoto == null) {
                            firstPhoto = meta;
                        }
                        coverage = s.coverage();
                    }
                });
                outcome = photo.name + ": " + photo.view.corners() + " corners" + photo.view.foundAs();
            } else {
                outcome = photo.name + " not used: " + photo.refusal; // the server's reason (no board, ...)
            }
            sessions.save(s); // the photo count moved either way
        } catch (InterruptedException e) {
            // the screen was left during the upload (its executor shut down): the shutter works on return
            Thread.currentThread().interrupt();
            shutterBack("Photo not sent: the screen was left during the upload. Take it again.");
            return;
        } catch (Exception e) {
            outcome = "Photo not sent: " + e.getMessage();
        }
        final String shown = outcome;
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                shutter.setEnabled(true);
                if (s != sessions.current()) {
                    return; // started over meanwhile
                }
                report.setText(shown);
                counts.setText(photoCounts());
                calibrate.setEnabled(firstPhoto != null);
                preview.invalidate();
            }
        });
    }

    private void calibrate() {
        final CalibrationSession s = sessions.current();
        final FrameMeta first = firstPhoto;
        final CameraFacts f = facts;
        if (s == null || first == null || f == null) {
            return;
        }
        calibrate.setEnabled(false);
        report.setText("Calibrating...");
        boolean queued = inBackground(new Runnable() {
            @Override
            public void run() {
                String text;
                boolean kept = false;
                try {
                    DeviceProfile phone = DeviceProfile.ofPhone(prefs.phoneProfileId(f.cameraId),
                            Build.MANUFACTURER + " " + Build.MODEL + " camera " + f.cameraId,
                            f.facing(), first.camera, first.width, first.height);
                    CalibrationSession.Outcome o = s.calibrate(phone, null);
                    if (o.report.ok) {
                        prefs.setCalibratedProfile(f.cameraId, o.report.profile);
                        kept = true;
                    } else {
                        coverage = s.coverage(); // the report's grid from now on
                        sessions.save(s);
                    }
                    text = o.describe();
                } catch (InterruptedException e) {
                    Thread.currentThread().interrupt();
                    text = "Calibration interrupted: the screen was left. Tap Calibrate again.";
                } catch (Exception e) {
                    text = "Calibration failed: " + e.getMessage();
                }
                final String shown = text;
                final boolean done = kept;
                runOnUiThread(new Runnable() {
                    @Override
                    public void run() {
                        if (done && s == sessions.current()) {
                            dropSession(); // the profile is kept: the next calibration starts afresh
                        } else {
                            calibrate.setEnabled(firstPhoto != null);
                        }
                        report.setText(shown);
                        preview.invalidate();
                    }
                });
            }
        });
        if (!queued) {
            calibrate.setEnabled(true);
        }
    }

    /** The coverage grid over the picture: red cells still to fill, green ones with enough corners. */
    private void drawCoverage(Canvas canvas, GreyPreview p) {
        BoardCoverage c = coverage;
        if (c == null || c.width != p.frameWidth || c.height != p.frameHeight) {
            c = BoardCoverage.forImage(p.frameWidth, p.frameHeight); // every cell still to fill
        }
        float cellW = (float) p.width / c.columns;
        float cellH = (float) p.height / c.rows;
        for (int r = 0; r < c.rows; r++) {
            for (int col = 0; col < c.columns; col++) {
                canvas.drawRect(col * cellW, r * cellH, (col + 1) * cellW, (r + 1) * cellH,
                        c.covered(r, col) ? covered : empty);
                canvas.drawRect(col * cellW, r * cellH, (col + 1) * cellW, (r + 1) * cellH, grid);
            }
        }
    }
}
