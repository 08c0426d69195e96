package io.lumipose.app;

import static org.junit.Assert.fail;
import static org.robolectric.Shadows.shadowOf;

import android.app.Activity;
import android.content.Context;
import android.content.SharedPreferences;
import android.os.Looper;
import android.view.View;
import android.view.ViewGroup;
import android.widget.Button;
import android.widget.TextView;

import java.lang.reflect.Field;
import java.nio.ByteBuffer;
import java.util.Arrays;
import java.util.concurrent.Callable;

import io.lumipose.client.camera.CameraFacts;
import io.lumipose.client.camera.Devices;
import io.lumipose.client.camera.FrameResult;
import io.lumipose.client.capture.CaptureOptions;
import io.lumipose.client.capture.CapturePlan;
import io.lumipose.client.flow.FrameSink;

/** What the screens' tests share: private state by name, waiting for the background, a camera's frames. */
final class Screens {
    private Screens() {
    }

    /** A field of {@code o} (its class or a superclass) by name. */
    @SuppressWarnings("unchecked")
    static <T> T get(Object o, String name) {
        try {
            return (T) field(o.getClass(), name).get(o);
        } catch (IllegalAccessException e) {
            throw new AssertionError(e);
        }
    }

    static void set(Object o, String name, Object value) {
        try {
            field(o.getClass(), name).set(o, value);
        } catch (IllegalAccessException e) {
            throw new AssertionError(e);
        }
    }

    private static Field field(Class<?> c, String name) {
        for (Class<?> k = c; k != null; k = k.getSuperclass()) {
            try {
                Field f = k.getDeclaredField(name);
                f.setAccessible(true);
                return f;
            } catch (NoSuchFieldException next) {
                // look further up
            }
        }
        throw new AssertionError("no field " + name + " in " + c);
    }

    /** Runs the main looper (posted UI work from background threads) until {@code done}, at most 10 s. */
    static void settle(String what, Callable<Boolean> done) {
        long until = System.currentTimeMillis() + 10_000;
        try {
            while (true) {
                shadowOf(Looper.getMainLooper()).idle();
                if (done.call()) {
                    return;
                }
                if (System.currentTimeMillis() > until) {
                    fail("timed out waiting for " + what);
                }
                Thread.sleep(20);
            }
        } catch (Exception e) {
            throw new AssertionError(e);
        }
    }

    static SharedPreferences prefs(Context c) {
        return c.getSharedPreferences("lumipose", Context.MODE_PRIVATE);
    }

    /** The settings' server URL. */
    static void server(Context c, String url) {
        prefs(c).edit().putString(Prefs.SERVER_URL, url).commit();
    }

    /** The first button of the screen whose text is {@code text}. */
    static Button button(Activity a, String text) {
        Button b = find(a.getWindow().getDecorView(), text);
        if (b == null) {
            throw new AssertionError("no button '" + text + "'");
        }
        return b;
    }

    private static Button find(View v, String text) {
        if (v instanceof Button && text.equals(((TextView) v).getText().toString())) {
            return (Button) v;
        }
        if (v instanceof ViewGroup) {
            ViewGroup g = (ViewGroup) v;
            for (int i = 0; i < g.getChildCount(); i++) {
                Button b = find(g.getChildAt(i), text);
                if (b != null) {
                    return b;
                }
            }
        }
        return null;
    }

    static String text(Object activity, String textViewField) {
        return Screens.<TextView>get(activity, textViewField).getText().toString();
    }

    /** A camera for the screens' tests: a fixture phone and its positioning plan. */
    static final class Camera {
        final CameraFacts facts = Devices.load(Devices.FRONT_270);
        final CapturePlan positioning;
        private long t = 1_000_000L;

        Camera() {
            try {
                positioning = CapturePlan.plan(facts, new CaptureOptions(8_400_000L, 0, 1, 2.0, 3_200_000L));
            } catch (Exception e) {
                throw new AssertionError(e);
            }
        }

        /** What the camera thread does once configured: the screen's sink for its own plan (null when paused). */
        FrameSink start(CameraActivity a) {
            try {
                return a.onStarted(facts, a.plan(facts, positioning), "test camera");
            } catch (Exception e) {
                throw new AssertionError(e);
            }
        }

        /** One frame (its result, then its image) of the screen's plan into {@code sink}. */
        void frame(CameraActivity a, FrameSink sink, int value) {
            CapturePlan plan;
            try {
                plan = a.plan(facts, positioning);
            } catch (Exception e) {
                throw new AssertionError(e);
            }
            t += 300_000_000L;
            sink.onResult(FrameResult.builder(t).exposureNs(plan.pose.exposureNs)
                    .sensitivityIso(plan.pose.sensitivityIso).build());
            int w = plan.output.width;
            byte[] b = new byte[w * plan.output.height];
            Arrays.fill(b, (byte) value);
            sink.onImage(t, ByteBuffer.wrap(b), w, plan.output.height, w, 1);
        }
    }

    /** Throws a checked exception where the signature does not declare it (a transport interrupted). */
    @SuppressWarnings("unchecked")
    static <E extends Throwable> void sneak(Throwable t) throws E {
        throw (E) t;
    }
}
