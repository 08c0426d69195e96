package io.lumipose.client.testutil;

import java.io.BufferedReader;
import java.io.ByteArrayOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.io.InputStreamReader;
import java.io.OutputStream;
import java.io.PrintStream;
import java.net.HttpURLConnection;
import java.net.ServerSocket;
import java.net.URL;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.List;
import java.util.concurrent.TimeUnit;

import org.json.JSONObject;

/**
 * The checkout's {@code lumipose} command (system property {@code lumipose.exe}, default
 * .venv/bin/lumipose) run with this checkout's Python code first on the path: {@code simulate}
 * to render fixtures, {@code serve} on a free port of 127.0.0.1. For the replay tests and the
 * bench (no JUnit here: failures are exceptions).
 */
public final class Lumipose {
    private Lumipose() {
    }

    /** The executable, or null when there is none. */
    public static Path executable() {
        String exe = System.getProperty("lumipose.exe");
        Path path = exe != null ? Paths.get(exe) : Repo.root().resolve(".venv/bin/lumipose");
        return Files.isExecutable(path) ? path : null;
    }

    private static ProcessBuilder command(List<String> args) {
        Path exe = executable();
        if (exe == null) {
            throw new IllegalStateException("no lumipose executable (set -Dlumipose.exe or run scripts/setup.sh)");
        }
        List<String> cmd = new ArrayList<String>();
        cmd.add(exe.toString());
        cmd.addAll(args);
        ProcessBuilder pb = new ProcessBuilder(cmd).directory(Repo.root().toFile()).redirectErrorStream(true);
        // The venv may be another checkout's: this checkout's code first.
        pb.environment().put("PYTHONPATH", Repo.root().toString());
        return pb;
    }

    /** {@code lumipose simulate SCENE OUT ARGS...}; throws with its output when it fails. */
    public static void simulate(String scene, Path out, String... args) throws IOException, InterruptedException {
        simulate(null, scene, out, args);
    }

    /** As {@link #simulate(String, Path, String...)}, its progress lines copied to {@code progress} as they come. */
    public static void simulate(final PrintStream progress, String scene, Path out, String... args)
            throws IOException, InterruptedException {
        List<String> cmd = new ArrayList<String>(Arrays.asList("simulate", scene, out.toString()));
        cmd.addAll(Arrays.asList(args));
        final Process p = command(cmd).start();
        final StringBuilder output = new StringBuilder();
        Thread reader = new Thread(new Runnable() {
            @Override
            public void run() {
                try (BufferedReader lines = new BufferedReader(new InputStreamReader(p.getInputStream(),
                        StandardCharsets.UTF_8))) {
                    for (String line; (line = lines.readLine()) != null; ) {
                        output.append(line).append('\n');
                        if (progress != null) {
                            progress.println(line);
                        }
                    }
                } catch (IOException e) {
                    output.append("(output lost: ").append(e.getMessage()).append(")");
                }
            }
        });
        reader.start();
        boolean done = p.waitFor(900, TimeUnit.SECONDS);
        if (!done) {
            p.destroyForcibly();
        }
        reader.join(5000);
        if (!done) {
            throw new IOException("lumipose " + cmd + " did not finish within 900 s: " + output);
        }
        if (p.exitValue() != 0) {
            throw new IOException("lumipose " + cmd + " failed (" + p.exitValue() + "): " + output);
        }
    }

    /** A running {@code lumipose serve} with its own data folder and API key; close() stops it. */
    public static final class Serve implements AutoCloseable {
        public static final String KEY = "replay-key";
        public final String baseUrl;
        private final Process process;
        private final Path log;

        private Serve(String baseUrl, Process process, Path log) {
            this.baseUrl = baseUrl;
            this.process = process;
            this.log = log;
        }

        /** Starts the server and waits (up to 90 s) until /healthz answers. */
        public static Serve start() throws IOException, InterruptedException {
            int port;
            try (ServerSocket s = new ServerSocket(0)) {
                port = s.getLocalPort();
            }
            Path data = Files.createTempDirectory("lumipose-replay");
            Path log = data.resolve("serve.log");
            Process p = command(Arrays.asList("serve", "--host", "127.0.0.1", "--port", String.valueOf(port),
                    "--data-dir", data.resolve("data").toString(), "--api-key", KEY, "--log-level", "warning"))
                    .redirectOutput(log.toFile()).start();
            Serve serve = new Serve("http://127.0.0.1:" + port, p, log);
            long deadline = System.nanoTime() + TimeUnit.SECONDS.toNanos(90);
            while (!serve.healthy()) {
                if (!p.isAlive()) {
                    throw new IOException("lumipose serve exited with " + p.exitValue() + ": " + serve.logTail());
                }
                if (System.nanoTime() > deadline) {
                    serve.close();
                    throw new IOException("lumipose serve did not answer /healthz within 90 s: " + serve.logTail());
                }
                Thread.sleep(200);
            }
            return serve;
        }

        private boolean healthy() {
            try {
                HttpURLConnection c = (HttpURLConnection) new URL(baseUrl + "/healthz").openConnection();
                c.setConnectTimeout(1000);
                c.setReadTimeout(2000);
                return c.getResponseCode() == 200;
            } catch (IOException e) {
                return false;
            }
        }

        /** PUT the map under its own name (the app names its map in every request). */
        public void putMap(JSONObject map) throws IOException {
            put("/v1/maps/" + map.getString("name"), map);
        }

        private void put(String path, JSONObject body) throws IOException {
            HttpURLConnection c = (HttpURLConnection) new URL(baseUrl + path).openConnection();
            c.setRequestMethod("PUT");
            c.setDoOutput(true);
            c.setRequestProperty("Content-Type", "application/json");
            c.setRequestProperty("X-API-Key", KEY);
            try (OutputStream out = c.getOutputStream()) {
                out.write(body.toString().getBytes(StandardCharsets.UTF_8));
            }
            if (c.getResponseCode() != 200) {
                InputStream error = c.getErrorStream();
                String answer = error == null ? "" : new String(readAll(error), StandardCharsets.UTF_8);
                throw new IOException("PUT " + path + ": HTTP " + c.getResponseCode() + " " + answer);
            }
        }

        private static byte[] readAll(InputStream in) throws IOException {
            ByteArrayOutputStream out = new ByteArrayOutputStream();
            byte[] buffer = new byte[8192];
            for (int n; (n = in.read(buffer)) > 0; ) {
                out.write(buffer, 0, n);
            }
            return out.toByteArray();
        }

        public String logTail() {
            try {
                String s = new String(Files.readAllBytes(log), StandardCharsets.UTF_8);
                return s.length() > 2000 ? s.substring(s.length() - 2000) : s;
            } catch (IOException e) {
                return "(no log: " + e.getMessage() + ")";
            }
        }

        @Override
        public void close() throws InterruptedException {
            process.destroy();
            if (!process.waitFor(10, TimeUnit.SECONDS)) {
                process.destroyForcibly().waitFor(10, TimeUnit.SECONDS);
            }
        }
    }
}
