package io.lumipose.app;

import java.lang.annotation.ElementType;
import java.lang.annotation.Retention;
import java.lang.annotation.RetentionPolicy;
import java.lang.annotation.Target;

/**
 * Code reached only behind a {@code Build.VERSION.SDK_INT >= value()} check, so it may use framework API
 * above the minSdk (28). The minSdk API check (animal-sniffer, app/pom.xml) skips what carries it: keep it
 * on small classes or methods whose every caller checks the level (docs/android.md, "Dex and API level checks").
 */
@Retention(RetentionPolicy.CLASS)
@Target({ElementType.TYPE, ElementType.METHOD, ElementType.CONSTRUCTOR})
@interface OnlyOnApi {
    /** The API level every caller checks for. */
    int value();
}
