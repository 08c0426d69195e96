package io.lumipose.app;

import android.widget.LinearLayout;
import android.widget.TextView;

import java.util.Locale;

import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.map.Track;
import io.lumipose.client.net.LocateResult;

/**
 * Live position: frames go up one at a time (the newest wins) and the map shows the fix and the track.
 * With "read beacon IDs" on, short-exposure ID frames are interleaved for rooms with several panels;
 * the server combines them per device (X-Lumipose-Device).
 */
public final class LiveActivity extends LocatingActivity {
    private final Track track = new Track(200);
    private BeaconMapView mapView;
    private TextView pose;

    @Override
    protected void buildViews() {
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        pose = new TextView(this);
        pose.setTextSize(20f);
        pose.setPadding(16, 16, 16, 16);
        mapView = new BeaconMapView(this);
        root.addView(pose);
        root.addView(mapView, new LinearLayout.LayoutParams(LinearLayout.LayoutParams.MATCH_PARENT, 0, 1f));
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
    public void onResult(FrameMeta meta, final LocateResult r) {
        if (!r.ok && "id".equals(meta.frameKind)) {
            return; // an ID frame feeds the server's ID evidence; its own "no fix" is no news
        }
        if (r.ok) {
            track.add(r.positionM());
        }
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                if (!r.ok) {
                    pose.setText("No fix: " + r.reason + (r.message == null ? "" : " - " + r.message));
                    return;
                }
                double[] p = r.positionM();
                double[] ypr = r.yawPitchRollDeg();
                pose.setText(String.format(Locale.US,
                        "x %.3f  y %.3f  z %.3f m%nbeacon %s (%s)%nyaw %.1f  pitch %.1f  roll %.1f deg",
                        p[0], p[1], p[2], r.beaconId == null ? "?" : String.valueOf(r.beaconId), r.beaconIdSource,
                        ypr == null ? Double.NaN : ypr[0], ypr == null ? Double.NaN : ypr[1],
                        ypr == null ? Double.NaN : ypr[2]));
                mapView.setTrack(track.snapshot(), p, ypr == null ? 0 : ypr[0]);
            }
        });
    }
}
