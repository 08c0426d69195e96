package io.lumipose.client.testutil;


import org.junit.jupiter.api.Assertions;
import org.junit.jupiter.api.Assumptions;

/** The set-up checks of the end-to-end tests against {@code lumipose serve} (JUnit's; {@link Lumipose} has none). */
public final class EndToEnd {
    private EndToEnd() {
    }

    /**
     * Without an executable the test class fails when {@code lumipose.e2e.required} is set
     * (scripts/android_test.sh), else it is skipped, saying why.
     */
    public static void assumeExecutable() {
        if (Lumipose.executable() == null) {
            if (Boolean.getBoolean("lumipose.e2e.required")) {
                Assertions.fail("no lumipose executable (lumipose.e2e.required=true)");
            }
            Assumptions.abort("no lumipose executable; run scripts/android_test.sh, which sets it up");
        }
    }
}
