package io.lumipose.app;

import android.content.Context;

import java.io.IOException;

/**
 * The session a screen works on (a survey, a calibration) and the file that keeps it across the
 * screen's recreation and the process's death: the one owner of "which session is the screen's".
 * Uploads run on other threads and end late; each asks {@link #save} to write the session it worked
 * on, which is written only while that session is still the screen's (not after Start over, a
 * finished run, or onDestroy, when the file is already the next instance's).
 *
 * @param <S> the session type; its JSON is {@link Encoder#json}'s, read back by the screen
 */
final class ScreenSession<S> {
    /** The file's text of a session (called under the file's lock, on any thread). */
    interface Encoder<S> {
        String json(S session);
    }

    private final SessionFile file;
    private final Encoder<S> encoder;
    private final SessionFile.Failure failure;
    private volatile S current;

    ScreenSession(Context context, String fileName, Encoder<S> encoder, SessionFile.Failure failure) {
        this.file = new SessionFile(context, fileName);
        this.encoder = encoder;
        this.failure = failure;
    }

    /** The screen's session, or null before the first photo and after Start over. */
    S current() {
        return current;
    }

    /** The saved text, or null when there is none (after the writes queued so far have landed). */
    String saved() throws IOException {
        return file.read();
    }

    /** The saved text could not be read back: drops it (a new session starts). */
    void discardSaved() {
        file.drop();
    }

    /** UI thread: {@code session} (new, or restored) becomes the screen's; a new one is written. */
    void adopt(S session, boolean write) {
        synchronized (file.lock()) {
            current = session;
        }
        if (write) {
            save(session);
        }
    }

    /**
     * Runs {@code change} under the file's lock if {@code session} is still the screen's (state kept
     * beside the session, such as the calibration's first photo, changes with it or not at all).
     */
    boolean ifCurrent(S session, Runnable change) {
        synchronized (file.lock()) {
            if (session != current) {
                return false;
            }
            change.run();
            return true;
        }
    }

    /** Any thread: queues {@code session}'s write, unless the screen has left it. */
    void save(S session) {
        synchronized (file.lock()) {
            if (session == current) {
                file.writeSoon(encoder.json(session), failure);
            }
        }
    }

    /**
     * onDestroy: the file is the next instance's from here on; an upload of this one that ends later
     * (its connection outlives the executor's shutdown) must not write its older session over it.
     */
    void leave() {
        synchronized (file.lock()) {
            current = null;
        }
    }

    /** UI thread: forgets the session and its file (Start over, or a finished run). */
    void forget() {
        leave(); // no write of it is queued from here on
        file.drop(); // outside the lock: it waits for the writes queued before, which take it
    }
}
