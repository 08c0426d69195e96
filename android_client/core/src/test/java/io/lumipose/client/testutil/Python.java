package io.lumipose.client.testutil;

import static org.junit.jupiter.api.Assertions.assertEquals;
import static org.junit.jupiter.api.Assertions.fail;

import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.Arrays;
import java.util.List;
import java.util.concurrent.TimeUnit;

import org.junit.jupiter.api.Assumptions;

/**
 * The checkout's Python (next to {@code lumipose.exe}, default .venv/bin), for tests that compare
 * the Java port of a function with the Python original. Missing: the test fails when
 * {@code lumipose.e2e.required} is set (scripts/android_test.sh), else it is skipped.
 */
public final class Python {
    private Python() {
    }

    public static Path executable() {
        String exe = System.getProperty("lumipose.exe");
        Path python = exe != null ? Paths.get(exe).resolveSibling("python") : Repo.root().resolve(".venv/bin/python");
        if (!Files.isExecutable(python)) {
            String reason = "Python of the checkout not found at " + python;
            if (Boolean.getBoolean("lumipose.e2e.required")) {
                fail(reason + " (lumipose.e2e.required=true)");
            }
            Assumptions.abort(reason + "; run scripts/android_test.sh, which sets it up");
        }
        return python;
    }

    /** Runs a script of the test resources with the checkout on the path; fails with its output. */
    public static void run(String resourceScript, String... args) throws IOException, InterruptedException {
        Path script = Repo.root().resolve("android_client/core/src/test/resources").resolve(resourceScript);
        List<String> cmd = new ArrayList<String>(Arrays.asList(executable().toString(), script.toString()));
        cmd.addAll(Arrays.asList(args));
        Path log = Files.createTempFile("python", ".log");
        ProcessBuilder pb = new ProcessBuilder(cmd).directory(Repo.root().toFile()).redirectErrorStream(true)
                .redirectOutput(log.toFile());
        pb.environment().put("PYTHONPATH", Repo.root().toString());
        Process p = pb.start();
        if (!p.waitFor(300, TimeUnit.SECONDS)) {
            p.destroyForcibly();
            fail(resourceScript + " did not finish within 300 s");
        }
        String output = new String(Files.readAllBytes(log), StandardCharsets.UTF_8);
        Files.delete(log);
        assertEquals(0, p.exitValue(), resourceScript + " failed: " + output);
    }
}
