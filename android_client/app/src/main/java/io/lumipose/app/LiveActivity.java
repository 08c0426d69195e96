package io.lumipose.app;

import android.os.SystemClock;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.util.Locale;
import java.util.Map;
import java.util.concurrent.ExecutorService;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.map.Track;
import io.lumipose.client.net.LocateResult;

/**
 * Live position: bursts go up one at a time and the map shows the fix and the server's
 * motion-filtered track (per device, X-Lumipose-Device). With "read beacon IDs" on and several
 * panels in the map, each pose frame is followed by short-exposure ID frames; only pose frames'
 * answers are shown. The screen also says what the capture plan noted and why frames stayed home.
 */
public final class LiveActivity extends LocatingActivity {
    private static final long DROPS_SHOWN_EVERY_MS = 1000;
    private final Track track = new Track(200);
    private BeaconMapView mapView;
    private TextView pose;
    private TextView notes;
    private volatile long dropsShownAtMs;

    @Override
    protected void buildViews() {
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        pose = new TextView(this);
        pose.setTextSize(20f);
        pose.setPadding(16, 16, 16, 16);
        notes = new TextView(this);
        notes.setPadding(16, 0, 16, 0);
        mapView = new BeaconMapView(this);
        root.addView(pose);
        root.addView(mapView, new LinearLayout.LayoutParams(LinearLayout.LayoutParams.MATCH_PARENT, 0, 1f));
        root.addView(notes);
        root.addView(status);
        setContentView(root);
    }

    @Override
    protected long idExposureNs() {
        return prefs.readIds() ? prefs.idExposureNs() : 0;
    }

    @Override
    protected void onMapLoaded(final RoomMap loaded) {
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                mapView.setMap(loaded);
            }
        });
    }

    @Override
    protected void onPose(FrameMeta meta, final LocateResult r) {
        final LocateResult.Track filtered = r.track();
        if (r.ok && filtered != null && !filtered.outlier) {
            track.add(filtered.filteredPositionM());
        }
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                if (!r.ok) {
                    pose.setText("No fix: " + r.reason + (r.message == null ? "" : " - " + r.message));
                    return;
                }
                double[] p = filtered != null ? filtered.filteredPositionM() : r.positionM();
                double[] ypr = r.yawPitchRollDeg();
                pose.setText(String.format(Locale.US,
                        "x %.3f  y %.3f  z %.3f m%s%nbeacon %s (%s)%nyaw %.1f  pitch %.1f  roll %.1f deg",
                        p[0], p[1], p[2], filtered == null ? " (fix, no track)" : filtered.outlier ? " (outlier)" : "",
                        r.beaconId == null ? "?" : String.valueOf(r.beaconId), r.beaconIdSource,
                        ypr == null ? Double.NaN : ypr[0], ypr == null ? Double.NaN : ypr[1],
                        ypr == null ? Double.NaN : ypr[2]));
                mapView.setTrack(track.snapshot(), p, ypr == null ? 0 : ypr[0]);
            }
        });
    }

    @Override
    public void onDropped(String reason) {
        long now = SystemClock.elapsedRealtime();
        if (now - dropsShownAtMs >= DROPS_SHOWN_EVERY_MS) {
            dropsShownAtMs = now;
            showNotes();
        }
    }

    private void showNotes() {
        CapturePlan p = plan;
        StringBuilder text = new StringBuilder();
        if (p != null) {
            for (String note : p.notes) {
                text.append(note).append('\n');
            }
        }
        for (String warning : warnings()) {
            text.append(warning).append('\n');
        }
        for (Map.Entry<String, Long> d : dropCounts().entrySet()) {
            text.append("not sent: ").append(d.getValue()).append(" (").append(d.getKey()).append(")\n");
        }
        final String shown = text.toString().trim();
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                notes.setText(shown);
            }
        });
    }

    @Override
    protected FrameSink frameSink(CameraFacts facts, CapturePlan plan, ExecutorService network) {
        FrameSink sink = super.frameSink(facts, plan, network);
        showNotes();
        return sink;
    }
}
