package io.lumipose.app;

import android.view.View;
import android.widget.Button;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.nio.ByteBuffer;
import java.util.Locale;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.atomic.AtomicBoolean;

import io.lumipose.client.bench.BenchCell;
import io.lumipose.client.bench.TestBenchGrid;
import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.FrameDescriber;
import io.lumipose.client.flow.FramePipeline;
import io.lumipose.client.flow.FrameSink;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.FrameUploader;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.StoredSample;

/**
 * Test-bench mode (paper Section II-B): walks the 391 cells from (-8, 11) to (8, -11); at each one
 * the user taps "Take sample", the next pose frame goes through the same FramePipeline as live
 * frames (described from its result, cut to the beacon's window) and is stored on the server with
 * the cell's label, and the screen shows the fix's 2-D error against the cell before moving on.
 * Uploads run on the screen's executor through the pipeline, which stops using it once paused.
 */
public final class BenchActivity extends CameraActivity implements FramePipeline.Listener {
    private final TestBenchGrid grid = TestBenchGrid.paper();
    /** The user asked for a sample and the pipeline has not taken a frame for it yet. */
    private final AtomicBoolean wanted = new AtomicBoolean(false);
    private volatile int index;
    /** The cell the sample in flight belongs to (the user may move on meanwhile). */
    private volatile BenchCell sampling;
    private volatile StoredSample stored;
    private volatile FramePipeline pipeline;
    private TextView cellView;
    private TextView resultView;
    private Button take;

    @Override
    protected void buildViews() {
        index = Math.max(0, Math.min(grid.size() - 1, prefs.benchIndex()));
        LinearLayout root = new LinearLayout(this);
        root.setOrientation(LinearLayout.VERTICAL);
        root.setPadding(24, 24, 24, 24);
        cellView = new TextView(this);
        cellView.setTextSize(30f);
        resultView = new TextView(this);
        resultView.setTextSize(18f);
        take = new Button(this);
        take.setText("Take sample");
        take.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                take.setEnabled(false);
                sampling = grid.cell(index);
                wanted.set(true);
            }
        });
        LinearLayout nav = new LinearLayout(this);
        nav.addView(button("Previous", -1));
        nav.addView(button("Skip", 1));
        root.addView(cellView);
        root.addView(take);
        root.addView(nav);
        root.addView(resultView);
        root.addView(status);
        setContentView(root);
        showCell();
    }

    private Button button(String text, final int step) {
        Button b = new Button(this);
        b.setText(text);
        b.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                move(step);
            }
        });
        return b;
    }

    private void move(int step) {
        index = Math.max(0, Math.min(grid.size() - 1, index + step));
        prefs.setBenchIndex(index);
        showCell();
    }

    private void showCell() {
        BenchCell c = grid.cell(index);
        double[] p = c.positionM();
        cellView.setText(String.format(Locale.US, "Cell %s  (%d of %d)%nx %.2f m, y %.2f m", c.label(), index + 1,
                grid.size(), p[0], p[1]));
    }

    @Override
    protected FrameSink frameSink(CameraFacts facts, CapturePlan plan, ExecutorService network) {
        FrameUploader storeSample = new FrameUploader() {
            @Override
            public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
                StoredSample s = client.storeSample(sampling.label(), luma, meta);
                stored = s;
                return s.result;
            }
        };
        FrameDescriber describer = new FrameDescriber(facts, plan, mapBearingDeg(),
                prefs.calibratedProfile(facts.cameraId));
        final FramePipeline p = FramePipeline.forCamera(describer, facts, plan, gravity.history(), gravity.rates(),
                storeSample, network, this);
        synchronized (sinkLock) {
            if (!current(network)) {
                p.close(); // the screen paused while it was built: onPause could not close it
                return null;
            }
            pipeline = p;
        }
        // Frames reach the pipeline only while a sample is wanted, until it has taken one.
        return new FrameSink() {
            @Override
            public void onResult(FrameResult result) {
                if (wanted.get()) {
                    long before = p.burstsSubmitted();
                    p.onResult(result);
                    closeGateIfTaken(p, before);
                }
            }

            @Override
            public void onImage(long timestampNs, ByteBuffer yPlane, int width, int height, int rowStride,
                                int pixelStride) {
                if (wanted.get()) {
                    long before = p.burstsSubmitted();
                    p.onImage(timestampNs, yPlane, width, height, rowStride, pixelStride);
                    closeGateIfTaken(p, before);
                }
            }
        };
    }

    private void closeGateIfTaken(FramePipeline p, long before) {
        if (p.burstsSubmitted() > before) {
            wanted.set(false);
        }
    }

    @Override
    protected void closeSinks() {
        FramePipeline p;
        synchronized (sinkLock) {
            p = pipeline;
            pipeline = null;
        }
        if (p != null) {
            p.close();
        }
        if (wanted.getAndSet(false)) {
            take.setEnabled(true);
        }
    }

    @Override
    public void onPoseResult(FrameMeta meta, LocateResult r) {
        StoredSample s = stored;
        BenchCell cell = sampling;
        String text = r.ok
                ? String.format(Locale.US, "Stored %s as %s: 2-D error %.1f mm", cell.label(), s.id,
                        cell.horizontalErrorMm(r.positionM()))
                : "Stored " + cell.label() + " as " + s.id + ": no fix (" + r.reason + ")";
        showSampleOutcome(text, true);
    }

    @Override
    public void onIdResult(FrameMeta meta, LocateResult result) {
        // The bench plan takes no ID frames.
    }

    @Override
    public void onDropped(String reason) {
        showStatus("Frame not sent: " + reason);
    }

    @Override
    public void onFailure(FrameMeta meta, Exception error) {
        showSampleOutcome("Sample " + sampling.label() + " not stored: " + error.getMessage(), false);
    }

    private void showSampleOutcome(final String text, final boolean advance) {
        runOnUiThread(new Runnable() {
            @Override
            public void run() {
                resultView.setText(text);
                take.setEnabled(true);
                if (advance) {
                    move(1);
                }
            }
        });
    }
}
