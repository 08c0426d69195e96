package io.lumipose.app;

import android.content.Context;
import android.graphics.Bitmap;
import android.graphics.Canvas;
import android.view.MotionEvent;
import android.view.View;

import io.lumipose.client.frame.GreyPreview;

/**
 * What the camera sees, as the sensor sees it (not turned to the screen): a small grey picture
 * (the core's {@link GreyPreview}) scaled to fit, with the screen's overlay drawn in the picture's
 * pixels, and taps handed back in the full frame's pixels.
 */
final class PreviewView extends View {
    /** Draws over the picture; the canvas is in preview pixels. */
    interface Overlay {
        void draw(Canvas canvas, GreyPreview preview);
    }

    /** A tap at the full frame's pixel (x, y). */
    interface TapListener {
        void onTap(double frameX, double frameY);
    }

    private GreyPreview preview;
    private Bitmap bitmap;
    private int[] argb;
    private Overlay overlay;
    private TapListener taps;
    private float scale = 1f;
    private float left;
    private float top;

    PreviewView(Context context) {
        super(context);
    }

    /** UI thread. */
    void show(GreyPreview p) {
        preview = p;
        // One bitmap while the picture keeps its size: a new one five times a second is garbage the
        // UI thread's collector must clear while the camera runs.
        if (bitmap == null || bitmap.getWidth() != p.width || bitmap.getHeight() != p.height) {
            bitmap = Bitmap.createBitmap(p.width, p.height, Bitmap.Config.ARGB_8888);
        }
        argb = p.argb(argb);
        bitmap.setPixels(argb, 0, p.width, 0, 0, p.width, p.height);
        invalidate();
    }

    GreyPreview shown() {
        return preview;
    }

    void setOverlay(Overlay o) {
        overlay = o;
        invalidate();
    }

    void setTapListener(TapListener t) {
        taps = t;
    }

    @Override
    protected void onDraw(Canvas canvas) {
        super.onDraw(canvas);
        GreyPreview p = preview;
        if (p == null || bitmap == null || getWidth() == 0 || getHeight() == 0) {
            return;
        }
        scale = Math.min((float) getWidth() / p.width, (float) getHeight() / p.height);
        left = (getWidth() - p.width * scale) / 2;
        top = (getHeight() - p.height * scale) / 2;
        canvas.save();
        canvas.translate(left, top);
        canvas.scale(scale, scale);
        canvas.drawBitmap(bitmap, 0, 0, null);
        if (overlay != null) {
            overlay.draw(canvas, p);
        }
        canvas.restore();
    }

    @Override
    public boolean onTouchEvent(MotionEvent event) {
        GreyPreview p = preview;
        if (taps == null || p == null || event.getAction() != MotionEvent.ACTION_UP) {
            return taps != null;
        }
        double x = (event.getX() - left) / scale;
        double y = (event.getY() - top) / scale;
        if (x >= 0 && y >= 0 && x < p.width && y < p.height) {
            taps.onTap(p.toFrameX(x), p.toFrameY(y));
        }
        return true;
    }
}
