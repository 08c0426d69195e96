package io.lumipose.client.testutil;

import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;

/** Files of the Lumipose checkout the tests read (golden examples, fixtures). */
public final class Repo {
    private Repo() {
    }

    /** The checkout root: system property lumipose.repo (set by the POM), else found upwards from here. */
    public static Path root() {
        String p = System.getProperty("lumipose.repo");
        if (p != null) {
            return Paths.get(p).toAbsolutePath().normalize();
        }
        Path d = Paths.get("").toAbsolutePath();
        while (d != null && !Files.isDirectory(d.resolve("shared_schemas"))) {
            d = d.getParent();
        }
        if (d == null) {
            throw new IllegalStateException("cannot find the Lumipose checkout (no shared_schemas/ above "
                    + Paths.get("").toAbsolutePath() + "); set -Dlumipose.repo");
        }
        return d;
    }

    public static Path file(String relative) {
        Path f = root().resolve(relative);
        if (!Files.isRegularFile(f)) {
            throw new IllegalStateException("missing repository file " + f);
        }
        return f;
    }

    public static String text(String relative) throws IOException {
        return new String(Files.readAllBytes(file(relative)), StandardCharsets.UTF_8);
    }
}
