package io.lumipose.app;

import android.graphics.Canvas;
import android.graphics.Color;
import android.graphics.Paint;
import android.os.Bundle;
import android.text.InputType;
import android.widget.Button;
import android.widget.EditText;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.io.IOException;
import java.nio.ByteBuffer;
import java.util.List;
import java.util.Locale;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.flow.StillCapture;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.frame.GreyPreview;
import io.lumipose.client.survey.SurveyReport;
import io.lumipose.client.survey.SurveySession;

/**
 * "Survey room": photos of the ceiling from the floor, each seeing two or more panels, taken as
 * positioning frames (pose exposure, gravity and compass bearing) but whole, stored as samples;
 * after each photo the user taps every panel on it with its ID, then the survey (POST /v1/surveys,
 * the map in use as the sketch, the chosen anchor) places every panel; on success the surveyed map
 * becomes the server's active map and the app's (docs/android.md, "Survey room").
 */
public final class SurveyActivity extends StillActivity implements PreviewView.TapListener {
    /** The session's file in the app's private storage (docs/android.md, "Sessions across recreation"). */
    static final String SESSION_FILE = "survey-session.json";
    private static final int ID_NAME = 1;
    private static final int ID_ANCHOR = 2;
    private static final int ID_PANEL = 3;
    private final Paint labelPaint = new Paint(Paint.ANTI_ALIAS_FLAG);
    private EditText nameField;
    private EditText anchorField;
    private EditText panelField;
    private TextView photosView;
    private TextView reportView;
    private Button surveyButton;
    /** The survey and its file: made on the first photo, restored, finished, started over on the UI thread. */
    private ScreenSession<SurveySession> sessions;
    /** The photo on screen for labelling (its index in the session), or -1 while the camera is shown. */
    private volatile int held = -1;

    @Override
    protected void buildViews() {
        labelPaint.setColor(Color.rgb(255, 60, 0));
        labelPaint.setTextSize(14f);
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        root.setPadding(16, 16, 16, 16);
        nameField = Forms.field(this, root, ID_NAME, "Surveyed map's name", prefs.mapName() + "-surveyed",
                InputType.TYPE_CLASS_TEXT);
        anchorField = Forms.field(this, root, ID_ANCHOR, "Anchor panel ID (its place in the map '" + prefs.mapName()
                + "' is kept)", "", InputType.TYPE_CLASS_NUMBER);
        panelField = Forms.field(this, root, ID_PANEL, "Panel ID: tap a panel on the photo to name it", "",
                InputType.TYPE_CLASS_NUMBER);
        surveyButton = addCameraViews(root, new PreviewView.Overlay() {
            @Override
            public void draw(Canvas canvas, GreyPreview p) {
                drawLabels(canvas, p);
            }
        }, "Survey", new Runnable() {
            @Override
            public void run() {
                survey();
            }
        });
        preview.setTapListener(this);
        Forms.button(this, root, "Start over", new Runnable() {
            @Override
            public void run() {
                startOver();
            }
        });
        photosView = new TextView(this);
        reportView = new TextView(this);
        root.addView(photosView);
        root.addView(reportView);
        root.addView(status);
        setContentView(root);
    }

    @Override
    protected void onCreate(Bundle savedInstanceState) {
        super.onCreate(savedInstanceState);
        sessions = new ScreenSession<SurveySession>(this, SESSION_FILE, new ScreenSession.Encoder<SurveySession>() {
            @Override
            public String json(SurveySession s) {
                return s.toJson().toString();
            }
        }, new SessionFile.Failure() {
            @Override
            public void failed(IOException e) {
                showStatus("The survey could not be saved on the phone: " + e.getMessage());
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
     * The session saved before the screen was recreated or the process died: its photos and labels,
     * back at the camera (the held photo's preview is not kept: labels go on the next photos). A file
     * that cannot be read is said, dropped, and a new survey starts.
     */
    private void restore() {
        SurveySession s;
        try {
            String text = sessions.saved();
            if (text == null) {
                return;
            }
            s = SurveySession.fromJson(client, text);
        } catch (IOException | IllegalArgumentException e) {
            sessions.discardSaved();
            reportView.setText("The survey saved on the phone could not be restored (" + e.getMessage()
                    + "): a new survey starts.");
            return;
        }
        sessions.adopt(s, false);
        nameField.setText(s.name());
        nameField.setEnabled(false);
        int n = s.shots().size();
        surveyButton.setEnabled(n > 0);
        reportView.setText("Survey '" + s.name() + "' restored: " + n + (n == 1 ? " photo" : " photos")
                + " stored on the server, listed below. Take the next photo, or tap Survey.");
        showPhotos();
    }

    /** UI thread: forgets the session and its file (the photos stay on the server as samples). */
    private void dropSession() {
        sessions.forget();
        held = -1;
        shutter.setText("Take photo");
        nameField.setEnabled(true);
        surveyButton.setEnabled(false);
        photosView.setText("");
    }

    private void startOver() {
        dropSession();
        reportView.setText("Started over: a new survey.");
    }

    /**
     * Survey photos see the panels as positioning frames do, but with no ID frames: one photo, whole;
     * at a still screen's rate (its preview is all that runs between photos).
     */
    @Override
    public CapturePlan plan(CameraFacts facts, CapturePlan positioning) throws UnsupportedCameraException {
        return positioning.withoutIdFrames("survey: panels named by labels, no ID frames")
                .atBurstsPerSecond(CaptureOptions.STILL_BURSTS_PER_S);
    }

    /** The sketch's positions are rough: its bearing (if any) is no better, but the compass bearing goes anyway. */
    @Override
    protected FrameDescriber describer(CameraFacts facts, CapturePlan plan) {
        return new FrameDescriber(facts, plan, mapBearingDeg(), prefs.calibratedProfile(facts.cameraId));
    }

    @Override
    protected void onShutter() {
        if (held >= 0) {
            held = -1; // back to the camera to aim the next photo
            shutter.setText("Take photo");
            return;
        }
        if (sessions.current() == null) {
            SurveySession s;
            try {
                s = new SurveySession(client, nameField.getText().toString().trim());
                nameField.setEnabled(false);
            } catch (IllegalArgumentException e) {
                reportView.setText("Map name: " + e.getMessage());
                return;
            }
            sessions.adopt(s, true);
        }
        takePhoto();
    }

    @Override
    protected void onPreviewShown(GreyPreview p) {
        if (held < 0) {
            super.onPreviewShown(p);
        }
    }

    @Override
    protected void handlePhoto(byte[] luma, FrameMeta meta) {
        final GreyPreview still = GreyPreview.of(ByteBuffer.wrap(luma), meta.width, meta.height, meta.width, 1,
                StillCapture.PREVIEW_SIDE);
        final SurveySession s = sessions.current();
        if (s == null) {
            shutterBack(null);
            return;
        }
        String outcome;
        int index = -1;
        try {
            SurveySession.Shot shot = s.addPhoto(luma, meta);
            index = s.shots().indexOf(shot); // not the last: the screen's other photo may be in flight
            sessions.save(s);
            outcome = "Photo " + (index + 1) + " stored as " + shot.sampleId + ": tap each panel with its ID."
                    + (meta.compassBearingDeg == null ? " (no compass reading)" : "");
        } catch (InterruptedException e) {
            // the screen was left during the upload (its executor shut down): the shutter works on return
            Thread.currentThread().interrupt();
            shutterBack("Photo not stored: the screen was left during the upload. Take it again.");
            return;
        } catch (Exception e) {
            outcome = "Photo not stored: " + e.getMessage();
        }
        final String shown = outcome;
        final int stored = index;
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                shutter.setEnabled(true);
                if (s != sessions.current()) {
                    return; // started over meanwhile: the photo belongs to the abandoned survey
                }
                reportView.setText(shown);
                if (stored >= 0) {
                    held = stored;
                    preview.show(still);
                    shutter.setText("Next photo");
                    surveyButton.setEnabled(true);
                }
                showPhotos();
            }
        });
    }

    @Override
    public void onTap(double frameX, double frameY) {
        SurveySession s = sessions.current();
        int index = held;
        if (s == null || index < 0) {
            return;
        }
        try {
            s.label(index, Integer.parseInt(panelField.getText().toString().trim()), frameX, frameY);
        } catch (NumberFormatException e) {
            reportView.setText("Type the panel's ID first, then tap the panel.");
            return;
        } catch (IllegalArgumentException e) {
            reportView.setText(e.getMessage());
            return;
        }
        sessions.save(s);
        preview.invalidate();
        showPhotos();
    }

    private void showPhotos() {
        SurveySession s = sessions.current();
        if (s == null) {
            return;
        }
        StringBuilder b = new StringBuilder();
        List<SurveySession.Shot> shots = s.shots();
        for (int i = 0; i < shots.size(); i++) {
            b.append("photo ").append(i + 1).append(": panels");
            for (SurveySession.Label l : shots.get(i).labels) {
                b.append(' ').append(l.beaconId);
            }
            b.append('\n');
        }
        photosView.setText(b.toString().trim());
    }

    /** The held photo's labels: a dot and the ID where the user tapped. */
    private void drawLabels(Canvas canvas, GreyPreview p) {
        SurveySession s = sessions.current();
        int index = held;
        if (s == null || index < 0) {
            return;
        }
        for (SurveySession.Label l : s.shots().get(index).labels) {
            float x = (float) (l.xPx / p.step);
            float y = (float) (l.yPx / p.step);
            canvas.drawCircle(x, y, 4f, labelPaint);
            canvas.drawText(String.valueOf(l.beaconId), x + 6, y - 6, labelPaint);
        }
    }

    private void survey() {
        final SurveySession s = sessions.current();
        final String sketch = prefs.mapName();
        final int anchor;
        try {
            anchor = Integer.parseInt(anchorField.getText().toString().trim());
        } catch (NumberFormatException e) {
            reportView.setText("Type the anchor panel's ID.");
            return;
        }
        if (s == null) {
            return;
        }
        surveyButton.setEnabled(false);
        reportView.setText("Surveying...");
        boolean queued = inBackground(new Runnable() {
            @Override
            public void run() {
                String text;
                boolean finished = false;
                try {
                    SurveyReport r = s.survey(sketch, anchor);
                    text = describe(r);
                    if (r.stored) {
                        s.activate(r);
                        prefs.setMapName(r.map.name);
                        text += "\nMap '" + r.map.name + "' is now the active map.";
                        finished = true;
                    }
                } catch (InterruptedException e) {
                    // the screen was left while the survey ran: sent once, so the map may be stored
                    Thread.currentThread().interrupt();
                    text = "The survey was interrupted (the screen was left). If map '" + s.name() + "' is on "
                            + "the server, make it active there rather than surveying again.";
                } catch (IOException e) {
                    // sent once: the server may still have stored the map
                    text = "No answer to the survey: " + e.getMessage() + "\nIf map '" + s.name() + "' is on the "
                            + "server, make it active there rather than surveying again.";
                } catch (Exception e) {
                    text = "Survey refused: " + e.getMessage();
                }
                final String shown = text;
                final boolean done = finished;
                runOnUiThread(new Runnable() {
                    @Override
                    public void run() {
                        if (done && s == sessions.current()) {
                            dropSession(); // stored and active: the next survey starts afresh
                        } else {
                            surveyButton.setEnabled(true);
                        }
                        reportView.setText(shown);
                    }
                });
            }
        });
        if (!queued) {
            surveyButton.setEnabled(true);
        }
    }

    private static String describe(SurveyReport r) {
        StringBuilder b = new StringBuilder(String.format(Locale.US, "%d frames used, RMS %.2f px", r.framesUsed,
                r.rmsPx));
        if (r.bearingDeg != null) {
            b.append(String.format(Locale.US, ", +X at compass bearing %.1f deg", r.bearingDeg));
            if (r.bearingSigmaDeg != null) {
                b.append(String.format(Locale.US, " (sigma %.1f)", r.bearingSigmaDeg));
            }
        }
        for (SurveyReport.SurveyedBeacon p : r.beacons) {
            double[] c = p.centerM();
            double[] sd = p.centerSigmaM();
            b.append(String.format(Locale.US, "%npanel %d: (%.3f, %.3f, %.3f) m +- (%.1f, %.1f, %.1f) mm, yaw %.2f"
                    + " +- %.2f deg, %d frames", p.beaconId, c[0], c[1], c[2], sd[0] * 1000, sd[1] * 1000,
                    sd[2] * 1000, p.yawDeg, p.yawSigmaDeg, p.frames));
        }
        for (SurveyReport.Skipped k : r.skipped) {
            b.append("\nskipped ").append(k.name).append(": ").append(k.why);
        }
        return b.toString();
    }
}
