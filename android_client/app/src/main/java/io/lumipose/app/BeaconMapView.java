package io.lumipose.app;

import android.content.Context;
import android.graphics.Canvas;
import android.graphics.Color;
import android.graphics.Paint;
import android.graphics.Path;
import android.view.View;

import java.util.Collections;
import java.util.List;

import io.lumipose.client.map.Beacon;
import io.lumipose.client.map.MapViewport;
import io.lumipose.client.map.RoomMap;

/** A small floor plan: the room's beacons, each in its shape, with their IDs, the recent track and the current pose. */
final class BeaconMapView extends View {
    /** Points per corner arc of a panel's outline: a circle is four of them. */
    private static final int OUTLINE_POINTS_PER_ARC = 12;
    private final Paint beaconPaint = new Paint(Paint.ANTI_ALIAS_FLAG);
    private final Paint textPaint = new Paint(Paint.ANTI_ALIAS_FLAG);
    private final Paint trackPaint = new Paint(Paint.ANTI_ALIAS_FLAG);
    private final Paint phonePaint = new Paint(Paint.ANTI_ALIAS_FLAG);
    private RoomMap map;
    private List<double[]> track = Collections.emptyList();
    private double[] current;
    private double yawDeg;

    BeaconMapView(Context context) {
        super(context);
        beaconPaint.setColor(Color.rgb(255, 190, 0));
        textPaint.setColor(Color.DKGRAY);
        textPaint.setTextSize(28f);
        trackPaint.setColor(Color.rgb(60, 120, 220));
        trackPaint.setStyle(Paint.Style.STROKE);
        trackPaint.setStrokeWidth(3f);
        phonePaint.setColor(Color.rgb(220, 40, 40));
        phonePaint.setStrokeWidth(5f);
    }

    void setMap(RoomMap m) {
        map = m;
        invalidate();
    }

    void setTrack(List<double[]> points, double[] currentM, double currentYawDeg) {
        track = points;
        current = currentM;
        yawDeg = currentYawDeg;
        invalidate();
    }

    @Override
    protected void onDraw(Canvas canvas) {
        super.onDraw(canvas);
        if (map == null || getWidth() < 100 || getHeight() < 100) {
            return;
        }
        MapViewport v = MapViewport.fit(map, track, getWidth(), getHeight(), 40, 1.0);
        for (Beacon b : map.beacons) {
            Path p = new Path();
            double[][] c = b.outlineXyM(OUTLINE_POINTS_PER_ARC);
            p.moveTo((float) v.screenX(c[0][0]), (float) v.screenY(c[0][1]));
            for (int i = 1; i < c.length; i++) {
                p.lineTo((float) v.screenX(c[i][0]), (float) v.screenY(c[i][1]));
            }
            p.close();
            canvas.drawPath(p, beaconPaint);
            double[] centre = b.centerM();
            canvas.drawText("#" + b.id, (float) v.screenX(centre[0]) + 12, (float) v.screenY(centre[1]) - 12,
                    textPaint);
        }
        if (track.size() > 1) {
            Path p = new Path();
            p.moveTo((float) v.screenX(track.get(0)[0]), (float) v.screenY(track.get(0)[1]));
            for (double[] q : track) {
                p.lineTo((float) v.screenX(q[0]), (float) v.screenY(q[1]));
            }
            canvas.drawPath(p, trackPaint);
        }
        if (current != null) {
            float x = (float) v.screenX(current[0]);
            float y = (float) v.screenY(current[1]);
            canvas.drawCircle(x, y, 10f, phonePaint);
            // Heading tick: yaw about +Z, drawn with map +Y up.
            double a = Math.toRadians(yawDeg);
            canvas.drawLine(x, y, x + (float) (40 * Math.cos(a)), y - (float) (40 * Math.sin(a)), phonePaint);
        }
    }
}
