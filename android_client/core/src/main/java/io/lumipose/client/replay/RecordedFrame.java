package io.lumipose.client.replay;

import java.io.File;
import java.io.IOException;
import java.io.RandomAccessFile;

import org.json.JSONObject;

import io.lumipose.client.camera.Intrinsics;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.json.ContractException;
import io.lumipose.client.json.Json;

/**
 * One frame of a {@code lumipose simulate} folder: NAME.y (raw Y8 at the JSON's row stride) and
 * NAME.json (the contract's frame JSON, with the renderer's ground truth). The pixels stay on
 * disk until asked for: a full-size frame is 20 MB.
 */
public final class RecordedFrame {
    public final String name;
    public final int width;
    public final int height;
    /** When the first row's exposure started (Camera2's SENSOR_TIMESTAMP), ns. */
    public final long timestampNs;
    /** "pose" or "id": what the frame was captured for. */
    public final String kind;
    public final double exposureS;
    public final double iso;
    /** Null when the renderer drew no rolling shutter. */
    public final Double rollingShutterSkewS;
    /** The camera the frame was rendered with (the contract's convention, pixel centres at integers). */
    public final Intrinsics camera;
    private final double[] gravityCamera;
    private final double[] angularVelocityCameraDps;
    private final double[] truthPositionM;
    private final File pixels;
    private final int fileRowStride;

    RecordedFrame(String name, JSONObject json, File pixels) {
        FrameMeta meta = FrameMeta.fromJson(json);
        if (!"Y8".equals(meta.format)) {
            throw new ContractException("format", name + ": the replay reads Y8 fixtures, got " + meta.format);
        }
        if (meta.camera == null) {
            throw new ContractException("camera", name + ": the replay needs the fixture's intrinsics, not a profile");
        }
        if (meta.timestampNs == null || meta.exposureS == null || meta.iso == null) {
            throw new ContractException("timestamp_ns", name + ": a replayed frame needs timestamp_ns, exposure_s "
                    + "and iso (a camera reports them for every frame)");
        }
        this.name = name;
        this.width = meta.width;
        this.height = meta.height;
        this.timestampNs = meta.timestampNs;
        this.kind = meta.frameKind == null ? "pose" : meta.frameKind;
        this.exposureS = meta.exposureS;
        this.iso = meta.iso;
        this.rollingShutterSkewS = meta.rollingShutterSkewS;
        this.camera = meta.camera;
        this.gravityCamera = meta.gravityCamera();
        this.angularVelocityCameraDps = meta.angularVelocityCameraDps();
        this.truthPositionM = truthPosition(json);
        this.pixels = pixels;
        this.fileRowStride = meta.rowStride;
        long expected = (long) meta.rowStride * meta.height;
        if (pixels.length() != expected) {
            throw new ContractException("row_stride", pixels + " holds " + pixels.length() + " bytes, row_stride * "
                    + "height = " + expected);
        }
    }

    private static double[] truthPosition(JSONObject json) {
        JSONObject truth = Json.optObject(json, "ground_truth", "ground_truth");
        return truth == null ? null : Json.optDoubles(truth, "position_m", "ground_truth.position_m", 3);
    }

    public boolean isIdFrame() {
        return "id".equals(kind);
    }

    /** Gravity (pointing down) in the camera frame as the renderer drew it, or null. */
    public double[] gravityCamera() {
        return gravityCamera == null ? null : gravityCamera.clone();
    }

    /**
     * The camera's rotation rate over the readout (camera frame, deg/s) when the fixture states
     * one ({@code lumipose simulate} writes none yet), else null.
     */
    public double[] angularVelocityCameraDps() {
        return angularVelocityCameraDps == null ? null : angularVelocityCameraDps.clone();
    }

    /** The camera's true position (map frame, m), or null when the fixture has no ground truth. */
    public double[] truthPositionM() {
        return truthPositionM == null ? null : truthPositionM.clone();
    }

    /** The pixels, width x height bytes row after row (the file's row padding left out). */
    public byte[] luma() throws IOException {
        byte[] out = new byte[width * height];
        RandomAccessFile file = new RandomAccessFile(pixels, "r");
        try {
            for (int row = 0; row < height; row++) {
                file.seek((long) row * fileRowStride);
                file.readFully(out, row * width, width);
            }
        } finally {
            file.close();
        }
        return out;
    }

    @Override
    public String toString() {
        return name + " (" + kind + ", " + width + "x" + height + ", t = " + timestampNs + " ns)";
    }
}
