package io.lumipose.client.e2e;

import java.io.IOException;
import java.io.PrintStream;
import java.nio.ByteBuffer;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.Collections;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.Locale;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.frame.BeaconWindow;
import io.lumipose.client.frame.FrameLevels;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.replay.RecordedFrame;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.replay.ReplayCamera;
import io.lumipose.client.testutil.Lumipose;
import io.lumipose.client.testutil.Repo;

/**
 * The JVM benchmark of the app's path (scripts/android_bench.sh, issue 12): full-size Mi 8 front
 * frames 1, 2 and 3 m below a panel, each distance two captures (a pose frame and its ID burst)
 * of a phone held still, played by the replay camera through the FramePipeline to a real
 * {@code lumipose serve}; every frame the app sends as a window is also sent whole, as another
 * device, to compare the fixes. Prints one JSON object (--json) or a table.
 *
 * <p>Upload latency is modelled, not measured: the bytes sent (body and headers) at 50 Mbit/s,
 * plus the time from request to answer on 127.0.0.1 (the server's time per request).
 */
public final class AndroidBench {
    static final double[] DISTANCES_M = {1.0, 2.0, 3.0};
    static final double LINK_BITS_PER_S = 50e6;
    static final int WARM_UP_ROUNDS = 5;
    static final int TIMED_ROUNDS = 15;
    static final double[] TARGETS = {0.10, 0.01, 150};
    static final String SCENE = "android_client/core/src/test/resources/replay/android-bench.json";

    public static void main(String[] args) throws Exception {
        boolean json = false;
        Path cache = Paths.get("android_client/target/android-bench");
        for (int i = 0; i < args.length; i++) {
            if ("--json".equals(args[i])) {
                json = true;
            } else if ("--cache".equals(args[i])) {
                cache = Paths.get(args[++i]);
            } else {
                throw new IllegalArgumentException("usage: AndroidBench [--json] [--cache DIR]");
            }
        }
        PrintStream progress = System.err;
        List<Recording> recordings = new ArrayList<Recording>();
        for (double d : DISTANCES_M) {
            recordings.add(render(cache, d, progress));
        }
        JSONObject report;
        progress.println("starting lumipose serve");
        try (Lumipose.Serve serve = Lumipose.Serve.start()) {
            serve.putMap(recordings.get(0).map());
            report = run(recordings, serve, progress);
        }
        System.out.println(json ? report.toString(2) : table(report));
    }

    /** The scene's two still captures at {@code distanceM} below the panel, rendered once into the cache. */
    static Recording render(Path cache, double distanceM, PrintStream progress) throws Exception {
        Path folder = cache.resolve(String.format(Locale.ROOT, "%.0fm", distanceM));
        Path complete = folder.resolve(".complete");
        JSONObject scene = new JSONObject(Repo.text(SCENE));
        double ceiling = scene.getJSONArray("beacons").getJSONObject(0).getJSONArray("center_m").getDouble(2);
        JSONObject pose = scene.getJSONObject("series").getJSONObject("path").getJSONArray("poses").getJSONObject(0);
        pose.getJSONArray("position_m").put(2, ceiling - distanceM);
        JSONArray poses = new JSONArray();
        for (int k = 0; k < 2; k++) {
            poses.put(new JSONObject(pose.toString()).put("t_s", 0.5 * k));
        }
        scene.getJSONObject("series").getJSONObject("path").put("poses", poses);
        String key = scene.toString();
        if (Files.isRegularFile(complete) && new String(Files.readAllBytes(complete), StandardCharsets.UTF_8)
                .equals(key)) {
            progress.printf("frames at %.0f m: cached in %s%n", distanceM, folder);
            return Recording.open(folder.toFile());
        }
        Files.createDirectories(cache);
        Path sceneFile = cache.resolve(String.format(Locale.ROOT, "scene-%.0fm.json", distanceM));
        Files.write(sceneFile, scene.toString(2).getBytes(StandardCharsets.UTF_8));
        progress.printf("rendering the frames at %.0f m (full size, pose and ID frames) into %s%n", distanceM, folder);
        Lumipose.simulate(progress, sceneFile.toString(), folder, "--bursts");
        Files.write(complete, key.getBytes(StandardCharsets.UTF_8));
        return Recording.open(folder.toFile());
    }

    static JSONObject run(List<Recording> recordings, Lumipose.Serve serve, PrintStream progress) throws Exception {
        JSONArray distances = new JSONArray();
        List<Double> allWindowMs = new ArrayList<Double>();
        List<Double> allFindMs = new ArrayList<Double>();
        List<Double> allLevelsMs = new ArrayList<Double>();
        List<Double> poseLatency = new ArrayList<Double>();
        // A device's first capture also starts its server session (the first ID decoding without a track).
        List<Double> laterPoseLatency = new ArrayList<Double>();
        List<Double> idLatency = new ArrayList<Double>();
        long sentBytes = 0;
        long planeBytes = 0;
        double maxDifference = 0;
        int compared = 0;
        for (int i = 0; i < recordings.size(); i++) {
            Recording recording = recordings.get(i);
            double distance = DISTANCES_M[i];
            progress.printf("replaying %.0f m%n", distance);
            String device = String.format(Locale.ROOT, "bench-%.0fm", distance);
            ReplayRun run = ReplayRun.play(recording, serve.baseUrl, device, true);
            List<Double> windowMs = new ArrayList<Double>();
            for (double[] cost : windowCost(recording)) {
                windowMs.add(cost[0] + cost[1]);
                allFindMs.add(cost[0]);
                allLevelsMs.add(cost[1]);
            }
            allWindowMs.addAll(windowMs);
            Kind pose = new Kind();
            Kind id = new Kind();
            JSONArray frames = new JSONArray();
            Map<RecordedFrame, Integer> captures = captureNumbers(recording);
            for (ReplayRun.Sent s : run.sent) {
                int capture = captures.get(s.frame);
                Kind kind = s.isId() ? id : pose;
                long plane = (long) s.frame.width * s.frame.height;
                long sent = s.window.bodyBytes + s.window.headerBytes;
                double compressMs = s.window.gzipped ? compressMs(s.frame, s.window.frame) : 0;
                double latency = compressMs + sent * 8 / LINK_BITS_PER_S * 1000 + s.window.ms;
                kind.add(sent, plane, s.window.ms, latency);
                (s.isId() ? idLatency : poseLatency).add(latency);
                if (!s.isId() && capture > 0) {
                    laterPoseLatency.add(latency);
                }
                sentBytes += sent;
                planeBytes += plane;
                LocateResult window = s.result();
                LocateResult whole = LocateResult.fromJson(s.whole.reply);
                JSONObject f = new JSONObject().put("frame", s.frame.name).put("kind", s.isId() ? "id" : "pose")
                        .put("capture", capture)
                        .put("bytes_sent", sent).put("plane_bytes", plane).put("server_ms", round(s.window.ms))
                        .put("compress_ms", round(compressMs))
                        .put("whole_server_ms", round(s.whole.ms)).put("latency_ms_at_50mbit", round(latency))
                        .put("ok", window.ok).put("reason", window.reason == null ? JSONObject.NULL : window.reason);
                if (window.ok && whole.ok) {
                    double difference = ReplayEndToEndTest.distanceMm(window.positionM(), whole.positionM());
                    maxDifference = Math.max(maxDifference, difference);
                    compared++;
                    pose.differences.add(difference);
                    f.put("fix_difference_mm", difference).put("beacon_id", window.beaconId)
                            .put("error_mm", round(ReplayEndToEndTest.distanceMm(window.positionM(),
                                    s.frame.truthPositionM())));
                } else if (!s.isId()) {
                    f.put("whole_ok", whole.ok).put("whole_reason", whole.reason == null ? JSONObject.NULL
                            : whole.reason);
                }
                frames.put(f);
            }
            distances.put(new JSONObject().put("distance_m", distance)
                    .put("frame_size", recording.frames().get(0).width + "x" + recording.frames().get(0).height)
                    .put("captures", run.poses().size()).put("pose", pose.json()).put("id", id.json())
                    .put("window_ms_median", round(median(windowMs))).put("drops", new JSONObject(run.drops))
                    .put("failures", new JSONArray(run.failures)).put("frames", frames));
        }
        JSONObject machine = new JSONObject().put("cores", Runtime.getRuntime().availableProcessors())
                .put("java", System.getProperty("java.version")).put("os", System.getProperty("os.name") + " "
                        + System.getProperty("os.arch"));
        double ratio = (double) sentBytes / planeBytes;
        double poseLatencyMax = poseLatency.isEmpty() ? Double.NaN : Collections.max(poseLatency);
        return new JSONObject()
                .put("upload_bytes_ratio", round4(ratio))
                .put("max_fix_difference_mm", compared == 0 ? JSONObject.NULL : (Object) maxDifference)
                .put("fixes_compared", compared)
                .put("window_ms_median", round(median(allWindowMs)))
                .put("window_ms_median_parts", new JSONObject().put("find", round(median(allFindMs)))
                        .put("levels", round(median(allLevelsMs))))
                .put("latency_ms_at_50mbit", round(poseLatencyMax))
                .put("latency_ms_at_50mbit_by_kind", new JSONObject()
                        .put("pose_max", round(poseLatencyMax)).put("pose_median", round(median(poseLatency)))
                        .put("pose_after_first_capture_max", laterPoseLatency.isEmpty() ? JSONObject.NULL
                                : (Object) round(Collections.max(laterPoseLatency)))
                        .put("id_max", idLatency.isEmpty() ? JSONObject.NULL
                                : (Object) round(Collections.max(idLatency)))
                        .put("id_median", idLatency.isEmpty() ? JSONObject.NULL : (Object) round(median(idLatency))))
                .put("targets", new JSONObject().put("upload_bytes_ratio", TARGETS[0])
                        .put("max_fix_difference_mm", TARGETS[1]).put("latency_ms_at_50mbit_pose", TARGETS[2]))
                .put("meets_targets", ratio <= TARGETS[0] && compared > 0 && maxDifference <= TARGETS[1]
                        && poseLatencyMax <= TARGETS[2])
                .put("model", "latency = gzip time on this JVM (pose windows) + (body + header bytes) * 8 / 50 Mbit/s"
                        + " + request-to-answer time on 127.0.0.1 (the server's, gunzip included);"
                        + " window_ms: BeaconWindow.find + FrameLevels.measure on the pose frames' padded planes,"
                        + " after "
                        + WARM_UP_ROUNDS + " warm-up rounds, median of " + TIMED_ROUNDS)
                .put("machine", machine)
                .put("distances", distances);
    }

    /** Each frame's capture (a pose frame and the ID frames taken after it), from 0, in the recording's order. */
    static Map<RecordedFrame, Integer> captureNumbers(Recording recording) {
        Map<RecordedFrame, Integer> out = new HashMap<RecordedFrame, Integer>();
        int capture = -1;
        for (RecordedFrame f : recording.frames()) {
            if (!f.isIdFrame()) {
                capture++;
            }
            out.put(f, Math.max(capture, 0));
        }
        return out;
    }

    /**
     * Phone-side cost of each pose frame's window, ms, after warm-up, on the plane as the camera
     * hands it over: {finding the window, measuring the plane's grey levels sent with it}.
     */
    static List<double[]> windowCost(Recording recording) throws Exception {
        List<ByteBuffer> planes = new ArrayList<ByteBuffer>();
        List<RecordedFrame> frames = new ArrayList<RecordedFrame>();
        for (RecordedFrame f : recording.frames()) {
            if (f.isIdFrame()) {
                continue;
            }
            int stride = ReplayCamera.rowStride(f.width);
            ByteBuffer plane = ByteBuffer.allocateDirect(stride * (f.height - 1) + f.width);
            byte[] luma = f.luma();
            for (int row = 0; row < f.height; row++) {
                plane.position(row * stride);
                plane.put(luma, row * f.width, f.width);
            }
            plane.clear();
            planes.add(plane);
            frames.add(f);
        }
        List<double[]> ms = new ArrayList<double[]>();
        for (int round = 0; round < WARM_UP_ROUNDS + TIMED_ROUNDS; round++) {
            for (int i = 0; i < planes.size(); i++) {
                RecordedFrame f = frames.get(i);
                int stride = ReplayCamera.rowStride(f.width);
                long start = System.nanoTime();
                BeaconWindow.find(planes.get(i), f.width, f.height, stride, 1);
                long found = System.nanoTime();
                FrameLevels.measure(planes.get(i), f.width, f.height, stride, 1);
                long measured = System.nanoTime();
                if (round >= WARM_UP_ROUNDS) {
                    ms.add(new double[] {(found - start) / 1e6, (measured - found) / 1e6});
                }
            }
        }
        return ms;
    }

    /** Sums over the frames of one kind at one distance. */
    static final class Kind {
        long sent;
        long planes;
        int frames;
        final List<Double> serverMs = new ArrayList<Double>();
        final List<Double> latencyMs = new ArrayList<Double>();
        final List<Double> differences = new ArrayList<Double>();

        void add(long bytes, long plane, double ms, double latency) {
            sent += bytes;
            planes += plane;
            frames++;
            serverMs.add(ms);
            latencyMs.add(latency);
        }

        JSONObject json() {
            if (frames == 0) {
                return new JSONObject().put("frames", 0);
            }
            return new JSONObject().put("frames", frames).put("bytes_sent_per_frame", sent / frames)
                    .put("upload_bytes_ratio", round4((double) sent / planes))
                    .put("server_ms_median", round(median(serverMs)))
                    .put("latency_ms_at_50mbit_median", round(median(latencyMs)))
                    .put("latency_ms_at_50mbit_max", round(Collections.max(latencyMs)))
                    .put("max_fix_difference_mm", differences.isEmpty() ? JSONObject.NULL
                            : (Object) Collections.max(differences));
        }
    }

    static double median(List<Double> values) {
        if (values.isEmpty()) {
            return Double.NaN;
        }
        List<Double> sorted = new ArrayList<Double>(values);
        Collections.sort(sorted);
        int n = sorted.size();
        return n % 2 == 1 ? sorted.get(n / 2) : (sorted.get(n / 2 - 1) + sorted.get(n / 2)) / 2;
    }

    static double round(double v) {
        return Math.round(v * 100) / 100.0;
    }

    static double round4(double v) {
        return Math.round(v * 10000) / 10000.0;
    }

    static String table(JSONObject r) {
        StringBuilder out = new StringBuilder();
        JSONObject m = r.getJSONObject("machine");
        out.append(String.format(Locale.ROOT, "Android JVM bench: %d cores, Java %s, %s%n", m.getInt("cores"),
                m.getString("java"), m.getString("os")));
        out.append(String.format(Locale.ROOT, "%8s %5s %6s %12s %8s %10s %12s %12s%n", "distance", "kind", "frames",
                "bytes/frame", "ratio", "server ms", "latency ms", "fix diff mm"));
        JSONArray ds = r.getJSONArray("distances");
        for (int i = 0; i < ds.length(); i++) {
            JSONObject d = ds.getJSONObject(i);
            for (String kind : new String[] {"pose", "id"}) {
                JSONObject k = d.getJSONObject(kind);
                if (k.getInt("frames") == 0) {
                    continue;
                }
                String difference = k.isNull("max_fix_difference_mm") ? "-"
                        : String.format(Locale.ROOT, "%.4f", k.getDouble("max_fix_difference_mm"));
                out.append(String.format(Locale.ROOT, "%7.0fm %5s %6d %12d %8.4f %10.1f %12.1f %12s%n",
                        d.getDouble("distance_m"), kind, k.getInt("frames"), k.getLong("bytes_sent_per_frame"),
                        k.getDouble("upload_bytes_ratio"), k.getDouble("server_ms_median"),
                        k.getDouble("latency_ms_at_50mbit_max"), difference));
            }
            out.append(String.format(Locale.ROOT, "%7.0fm window (find + levels) median %.2f ms; drops %s%n",
                    d.getDouble("distance_m"), d.getDouble("window_ms_median"), d.get("drops")));
        }
        out.append(String.format(Locale.ROOT, "upload_bytes_ratio %s (target <= %s)%n", r.get("upload_bytes_ratio"),
                TARGETS[0]));
        out.append(String.format(Locale.ROOT, "max_fix_difference_mm %s over %d fixes (target <= %s)%n",
                r.get("max_fix_difference_mm"), r.getInt("fixes_compared"), TARGETS[1]));
        out.append(String.format(Locale.ROOT, "window_ms_median %s%n", r.get("window_ms_median")));
        out.append(String.format(Locale.ROOT, "latency_ms_at_50mbit (pose, max) %s (target <= %s); by kind %s%n",
                r.get("latency_ms_at_50mbit"), TARGETS[2], r.get("latency_ms_at_50mbit_by_kind")));
        out.append("meets targets: ").append(r.get("meets_targets")).append('\n');
        return out.toString();
    }

    /** The phone-side cost of compressing a gzipped window (LumiposeClient.gzip), on this JVM: median of 5 after 2. */
    static double compressMs(RecordedFrame frame, JSONObject meta) throws IOException {
        JSONObject crop = meta.getJSONObject("crop");
        int width = meta.getInt("width");
        int height = meta.getInt("height");
        byte[] plane = frame.luma();
        byte[] window = new byte[width * height];
        for (int row = 0; row < height; row++) {
            System.arraycopy(plane, (crop.getInt("y") + row) * frame.width + crop.getInt("x"), window, row * width, width);
        }
        List<Double> ms = new ArrayList<Double>();
        for (int i = 0; i < 7; i++) {
            long start = System.nanoTime();
            LumiposeClient.gzip(window);
            if (i >= 2) {
                ms.add((System.nanoTime() - start) / 1e6);
            }
        }
        Collections.sort(ms);
        return ms.get(ms.size() / 2);
    }
}
