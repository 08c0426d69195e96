package io.lumipose.app;

import android.view.View;
import android.widget.Button;
import android.widget.LinearLayout;
import android.widget.TextView;

import java.util.Locale;
import java.util.concurrent.atomic.AtomicBoolean;

import io.lumipose.client.bench.BenchCell;
import io.lumipose.client.bench.TestBenchGrid;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.StoredSample;

/**
 * Test-bench mode (paper Section II-B): walks the 391 cells from (-8, 11) to (8, -11); at each one
 * the user taps "Take sample", the next frame is stored on the server with the cell's label, and
 * the screen shows the fix's 2-D error against the cell before moving on.
 */
public final class BenchActivity extends CameraActivity {
    private final TestBenchGrid grid = TestBenchGrid.paper();
    private final AtomicBoolean wanted = new AtomicBoolean(false);
    private volatile int index;
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
    public boolean wantFrame() {
        return wanted.get();
    }

    @Override
    protected void handleFrame(final byte[] luma, final FrameMeta meta) {
        if (!wanted.compareAndSet(true, false)) {
            return;
        }
        final BenchCell cell = grid.cell(index);
        network.execute(new Runnable() {
            @Override
            public void run() {
                String text;
                boolean advance = false;
                try {
                    StoredSample s = client.storeSample(cell.label(), luma, meta);
                    text = s.result.ok
                            ? String.format(Locale.US, "Stored %s as %s: 2-D error %.1f mm", cell.label(), s.id,
                                    cell.horizontalErrorMm(s.result.positionM()))
                            : "Stored " + cell.label() + " as " + s.id + ": no fix (" + s.result.reason + ")";
                    advance = true;
                } catch (Exception e) {
                    text = "Sample " + cell.label() + " not stored: " + e.getMessage();
                }
                final String shown = text;
                final boolean next = advance;
                runOnUiThread(new Runnable() {
                    @Override
                    public void run() {
                        resultView.setText(shown);
                        take.setEnabled(true);
                        if (next) {
                            move(1);
                        }
                    }
                });
            }
        });
    }
}
