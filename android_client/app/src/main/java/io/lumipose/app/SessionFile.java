package io.lumipose.app;

import android.content.Context;

import java.io.ByteArrayOutputStream;
import java.io.File;
import java.io.FileInputStream;
import java.io.FileOutputStream;
import java.io.IOException;
import java.io.InputStream;
import java.nio.charset.StandardCharsets;

/**
 * A screen's session kept as one JSON file in the app's private storage ({@code getFilesDir()}),
 * written after every change and read back in onCreate: it survives the screen's recreation and the
 * process's death, which a Bundle (1 MB binder limit, and the views' corners are hundreds each) would
 * not for long sessions (docs/android.md, "Sessions across recreation"). Written whole to a
 * temporary file then renamed, so a kill mid-write leaves the previous file. Any thread; the screen
 * holds the object's lock around "is this still my session" and the write (see {@link #lock}).
 */
final class SessionFile {
    private final File file;
    private final File temporary;

    SessionFile(Context context, String name) {
        File dir = context.getFilesDir();
        file = new File(dir, name);
        temporary = new File(dir, name + ".tmp");
    }

    /** The lock to hold while checking the session is still the screen's and writing it. */
    Object lock() {
        return this;
    }

    /** The saved text, or null when there is none. */
    synchronized String read() throws IOException {
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

    synchronized void write(String json) throws IOException {
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
    synchronized void drop() {
        file.delete();
        temporary.delete();
    }
}
