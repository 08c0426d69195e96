package io.lumipose.app;

import android.graphics.Color;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.util.Locale;

import io.lumipose.client.calibration.AlignmentGuide;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.RoomMap;
import io.lumipose.client.net.LocateResult;

/**
 * Alignment mode (the paper's "calibration", Fig. 2b): guides the user until the camera sits
 * straight under the beacon centre, so the test-bench grid can be anchored with its origin there.
 * (The camera's own calibration is {@link CameraCalibrationActivity}.)
 */
public final class AlignmentActivity extends LocatingActivity {
    private final AlignmentGuide guide = new AlignmentGuide(0.001, 0.5);
    private TextView hint;
    private TextView numbers;

    @Override
    protected void buildViews() {
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        root.setPadding(24, 24, 24, 24);
        hint = new TextView(this);
        hint.setTextSize(26f);
        hint.setText("Place the phone under the panel, camera up.");
        numbers = new TextView(this);
        numbers.setTextSize(18f);
        root.addView(hint);
        root.addView(numbers);
        root.addView(status);
        setContentView(root);
    }

    @Override
    protected void onPose(FrameMeta meta, LocateResult r) {
        RoomMap m = map;
        Beacon b = m == null ? null : r.beaconId != null ? m.beacon(r.beaconId) : m.beacons.get(0);
        if (b == null) {
            showStatus("Beacon " + r.beaconId + " is not in map '" + prefs.mapName() + "'.");
            return;
        }
        final AlignmentGuide.Alignment a = guide.evaluate(r, b);
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                hint.setText(a.hint);
                hint.setTextColor(a.aligned ? Color.rgb(0, 140, 0) : Color.BLACK);
                numbers.setText(a.located ? String.format(Locale.US, "offset x %.1f mm, y %.1f mm, tilt %.2f deg",
                        a.offsetXM * 1000, a.offsetYM * 1000, a.tiltDeg) : "");
            }
        });
    }
}
