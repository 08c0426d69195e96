package io.lumipose.client.net;

/** Waits between retries; tests pass one that records instead of sleeping. */
public interface Sleeper {
    void sleep(long ms) throws InterruptedException;

    Sleeper REAL = new Sleeper() {
        @Override
        public void sleep(long ms) throws InterruptedException {
            Thread.sleep(ms);
        }
    };
}
