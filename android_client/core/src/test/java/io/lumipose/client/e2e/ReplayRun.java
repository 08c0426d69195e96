package io.lumipose.client.e2e;

import java.io.IOException;
import java.util.ArrayList;
import java.util.Collections;
import java.util.HashMap;
import java.util.List;
import java.util.Map;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.TimeUnit;

import org.json.JSONArray;
import org.json.JSONObject;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.capture.UnsupportedCameraException;
import io.lumipose.client.flow.FramePipeline;
import io.lumipose.client.frame.FrameMeta;
import io.lumipose.client.net.ClientConfig;
import io.lumipose.client.net.FrameUploader;
import io.lumipose.client.net.LocateResult;
import io.lumipose.client.net.LumiposeClient;
import io.lumipose.client.net.Sleeper;
import io.lumipose.client.replay.RecordedFrame;
import io.lumipose.client.replay.Recording;
import io.lumipose.client.replay.ReplayCamera;
import io.lumipose.client.sensor.GravityHistory;
import io.lumipose.client.sensor.GyroHistory;
import io.lumipose.client.testutil.Lumipose;

/**
 * One replay of a recording through the app's path (replay camera, plan, FramePipeline, burst
 * uploader, LumiposeClient) to a real server, with what was sent and what came back. The camera
 * waits before each call until the uploader is idle, so every burst is sent (a phone taking 2
 * captures a second against a server on the same desk) and the run does not depend on thread
 * timing: BurstUploader counts a burst just submitted as waiting until its thread takes it, so
 * a pose frame right behind a submit would be dropped as "busy" now and then.
 *
 * <p>With {@code compareWhole}, every frame the app sends as a window is also sent whole (the
 * same frame JSON without the crop, the recorded plane) as another device, so both answers can be
 * compared frame by frame.
 */
final class ReplayRun {
    /** One frame the app sent, with its answer; {@code whole} is the whole-frame upload's, when compared. */
    static final class Sent {
        final RecordedFrame frame;
        final CountingTransport.Exchange window;
        final CountingTransport.Exchange whole;

        Sent(RecordedFrame frame, CountingTransport.Exchange window, CountingTransport.Exchange whole) {
            this.frame = frame;
            this.window = window;
            this.whole = whole;
        }

        boolean isId() {
            return window.isId();
        }

        /** The answer to the window upload. */
        LocateResult result() {
            return LocateResult.fromJson(window.reply);
        }
    }

    final CapturePlan plan;
    final CameraFacts facts;
    /** In the order sent. */
    final List<Sent> sent;
    final List<FrameMeta> poseResults;
    final List<FrameMeta> idResults;
    final Map<String, Long> drops;
    final List<String> failures;

    private ReplayRun(CapturePlan plan, CameraFacts facts, List<Sent> sent, List<FrameMeta> poseResults, List<FrameMeta> idResults,
                      Map<String, Long> drops, List<String> failures) {
        this.plan = plan;
        this.facts = facts;
        this.sent = sent;
        this.poseResults = poseResults;
        this.idResults = idResults;
        this.drops = drops;
        this.failures = failures;
    }

    /** The app's live client (one attempt, no gzip, the map named), over a counting transport. */
    static LumiposeClient client(String baseUrl, String device, String map, CountingTransport transport) {
        ClientConfig config = ClientConfig.live(baseUrl, Lumipose.Serve.KEY, device, map);
        return new LumiposeClient(config, transport, Sleeper.REAL);
    }

    /** Beacons in a map JSON. */
    static int beacons(JSONObject map) {
        JSONArray b = map.getJSONArray("beacons");
        return b.length();
    }

    static ReplayRun play(Recording recording, String baseUrl, String device, boolean compareWhole)
            throws IOException, InterruptedException, UnsupportedCameraException {
        return play(recording, baseUrl, device, compareWhole, 0);
    }

    /** @param settingsLagFrames frames a request's settings lag behind it (0: per-frame control) */
    static ReplayRun play(Recording recording, String baseUrl, String device, boolean compareWhole,
                          int settingsLagFrames) throws IOException, InterruptedException, UnsupportedCameraException {
        ReplayCamera camera = new ReplayCamera(recording, 12, settingsLagFrames);
        CameraFacts facts = camera.facts();
        JSONObject map = recording.map();
        CaptureOptions options = camera.captureOptions(beacons(map), ceilingDistanceM(recording, map));
        CapturePlan plan = CapturePlan.plan(facts, options);

        final Map<Long, RecordedFrame> byTimestamp = new HashMap<Long, RecordedFrame>();
        for (RecordedFrame f : recording.frames()) {
            byTimestamp.put(f.timestampNs, f);
        }
        final CountingTransport windowTransport = new CountingTransport();
        final CountingTransport wholeTransport = new CountingTransport();
        String mapName = map.getString("name");
        final LumiposeClient app = client(baseUrl, device, mapName, windowTransport);
        final LumiposeClient whole = compareWhole
                ? client(baseUrl, device + "-whole", mapName, wholeTransport) : null;
        FrameUploader uploader = new FrameUploader() {
            @Override
            public LocateResult upload(byte[] luma, FrameMeta meta) throws Exception {
                LocateResult answer = app.upload(luma, meta);
                if (whole != null) {
                    whole.upload(byTimestamp.get(meta.timestampNs).luma(), wholeFrame(meta));
                }
                return answer;
            }
        };
        final List<FrameMeta> poseResults = Collections.synchronizedList(new ArrayList<FrameMeta>());
        final List<FrameMeta> idResults = Collections.synchronizedList(new ArrayList<FrameMeta>());
        final List<String> failures = Collections.synchronizedList(new ArrayList<String>());
        GravityHistory gravity = new GravityHistory();
        GyroHistory rates = new GyroHistory();
        ExecutorService network = Executors.newSingleThreadExecutor();
        final FramePipeline pipeline = FramePipeline.forCamera(facts, plan, null, gravity, rates,
                uploader, network, new FramePipeline.Listener() {
                    @Override
                    public void onPoseResult(FrameMeta meta, LocateResult result) {
                        poseResults.add(meta);
                    }

                    @Override
                    public void onIdResult(FrameMeta meta, LocateResult result) {
                        idResults.add(meta);
                    }

                    @Override
                    public void onDropped(String reason) {
                    }

                    @Override
                    public void onFailure(FrameMeta meta, Exception error) {
                        failures.add(meta.timestampNs + ": " + error);
                    }
                });
        camera.play(plan, pipeline, gravity, rates, new ReplayCamera.Pace() {
            @Override
            public void beforeDelivery(RecordedFrame frame) throws InterruptedException {
                waitIdle(pipeline);
            }
        });
        waitIdle(pipeline);
        pipeline.close();
        network.shutdown();
        network.awaitTermination(60, TimeUnit.SECONDS);

        List<CountingTransport.Exchange> wholes = wholeTransport.exchanges();
        List<Sent> sent = new ArrayList<Sent>();
        for (CountingTransport.Exchange e : windowTransport.exchanges()) {
            CountingTransport.Exchange w = null;
            for (CountingTransport.Exchange candidate : wholes) {
                if (candidate.timestampNs() == e.timestampNs()) {
                    w = candidate;
                }
            }
            sent.add(new Sent(byTimestamp.get(e.timestampNs()), e, w));
        }
        return new ReplayRun(plan, facts, sent, poseResults, idResults, pipeline.dropCounts(), failures);
    }

    private static void waitIdle(FramePipeline pipeline) throws InterruptedException {
        long deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(120);
        while (pipeline.uploading()) {
            if (System.nanoTime() > deadline) {
                throw new IllegalStateException("the uploader is still busy after 120 s");
            }
            Thread.sleep(2);
        }
    }

    /** Where the phone focuses: from the first frame's true height to the highest beacon (the app's setting). */
    private static double ceilingDistanceM(Recording recording, JSONObject map) {
        double ceiling = 0;
        JSONArray beacons = map.getJSONArray("beacons");
        for (int i = 0; i < beacons.length(); i++) {
            ceiling = Math.max(ceiling, beacons.getJSONObject(i).getJSONArray("center_m").getDouble(2));
        }
        double[] truth = recording.frames().get(0).truthPositionM();
        return truth != null && ceiling - truth[2] > 0.1 ? ceiling - truth[2] : 1.5;
    }

    /** The frame JSON of the whole frame a window was cut from. */
    static FrameMeta wholeFrame(FrameMeta window) {
        if (window.crop == null) {
            return window;
        }
        JSONObject o = window.toJson();
        o.remove("crop");
        o.put("width", window.fullWidth());
        o.put("height", window.fullHeight());
        o.put("row_stride", window.fullWidth());
        return FrameMeta.fromJson(o);
    }

    /** The pose frames sent, in order. */
    List<Sent> poses() {
        List<Sent> out = new ArrayList<Sent>();
        for (Sent s : sent) {
            if (!s.isId()) {
                out.add(s);
            }
        }
        return out;
    }
}
