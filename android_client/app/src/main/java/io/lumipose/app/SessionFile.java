package io.lumipose.app;

import android.content.Context;

import java.io.ByteArrayOutputStream;
import java.io.File;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.nio.charset.StandardCharsets;
import java.util.concurrent.ConcurrentHashMap;
import java.util.concurrent.ExecutionException;
import java.util.concurrent.ExecutorService;
import java.util.concurrent.Executors;
import java.util.concurrent.ThreadFactory;
import java.util.concurrent.TimeUnit;
import java.util.concurrent.TimeoutException;

/**
 * A screen's session kept as one JSON file in the app's private storage ({@code getFilesDir()}),
 * written after every change and read back in onCreate: it survives the screen's recreation and the
 * process's death, which a Bundle (1 MB binder limit, and the views' corners are hundreds each) would
 * not for long sessions (docs/android.md, "Sessions across recreation"). Written whole to a
 * temporary file then renamed, so a kill mid-write leaves the previous file. Any thread; the screen
 * holds the file's lock around "is this still my session" and queueing the write (see {@link #lock}).
 */
final class SessionFile {
    /**
     * One lock per file, not per screen: a recreated screen and its old instance (whose upload may
     * still be running) share the file.
     */
    private static final ConcurrentHashMap<String, Object> LOCKS = new ConcurrentHashMap<String, Object>();
    private final File file;
    private final File temporary;
    private final Object lock;

    SessionFile(Context context, String name) {
        File dir = context.getFilesDir();
        file = new File(dir, name);
        temporary = new File(dir, name + ".tmp");
        Object mine = new Object();
        Object shared = LOCKS.putIfAbsent(file.getAbsolutePath(), mine);
        lock = shared != null ? shared : mine;
    }

    /** The lock to hold while checking the session is still the screen's and writing it. */
    Object lock() {
        return lock;
    }

    /** What a write that failed does (on the writer thread). */
    interface Failure {
        void failed(IOException e);
    }

    /**
     * Writes go to one thread of the app's, in order, never shut down: not the UI thread (an fsync
     * there is jank) and not the screen's executor, whose shutdown on pause would drop a queued write.
     */
    private static final ExecutorService WRITER = Executors.newSingleThreadExecutor(new ThreadFactory() {
        @Override
        public Thread newThread(Runnable r) {
            Thread t = new Thread(r, "lumipose-session-writer");
            t.setDaemon(true);
            return t;
        }
    });
    /** How long a read waits for the writes queued before it. */
    private static final long FLUSH_TIMEOUT_MS = 5000;

    /** Any thread: {@code json} written after the writes queued before it; {@code failure} told if it fails. */
    void writeSoon(final String json, final Failure failure) {
        WRITER.execute(new Runnable() {
            @Override
            public void run() {
                try {
                    write(json);
                } catch (IOException e) {
                    failure.failed(e);
                }
            }
        });
    }

    /** The saved text, or null when there is none; after the writes queued so far have landed. */
    String read() throws IOException {
        flush();
        synchronized (lock) {
            return readLocked();
        }
    }

    /** Waits for the writes queued so far to land. */
    private static void flush() throws IOException {
        try {
            WRITER.submit(new Runnable() {
                @Override
                public void run() {
                }
            }).get(FLUSH_TIMEOUT_MS, TimeUnit.MILLISECONDS);
        } catch (InterruptedException e) {
            Thread.currentThread().interrupt();
            throw new IOException("interrupted while the session's last change was written");
        } catch (ExecutionException | TimeoutException e) {
            throw new IOException("the session's last change was not written in time: " + e);
        }
    }

    private String readLocked() throws IOException {
        if (!file.exists()) {
            return null;
        }
        InputStream in = new FileInputStream(file);
        try {
            ByteArrayOutputStream out = new ByteArrayOutputStream((int) Math.min(file.length(), 1 << 24));
            byte[] buffer = new byte[16384];
            for (int n = in.read(buffer); n > 0; n = in.read(buffer)) {
                out.write(buffer, 0, n);
            }
            return new String(out.toByteArray(), StandardCharsets.UTF_8);
        } finally {
            in.close();
        }
    }

    void write(String json) throws IOException {
        synchronized (lock) {
            writeLocked(json);
        }
    }

    private void writeLocked(String json) throws IOException {
        FileOutputStream out = new FileOutputStream(temporary);
        try {
            out.write(json.getBytes(StandardCharsets.UTF_8));
            out.getFD().sync();
        } finally {
            out.close();
        }
        if (!temporary.renameTo(file)) {
            throw new IOException("cannot rename " + temporary + " to " + file);
        }
    }

    /** Drops the file (the session finished, or the user started over, or it could not be read). */
    /** Call without holding {@link #lock}: the writes queued before take it. */
    void drop() {
        try {
            flush(); // the writes queued before it first, or one of them would bring the file back
        } catch (IOException e) {
            // deleted all the same: a write still queued belongs to the session being dropped
        }
        synchronized (lock) {
            file.delete();
            temporary.delete();
        }
    }
}
