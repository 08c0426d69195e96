package io.lumipose.app;

import android.content.Context;
import android.view.View;
import android.widget.Button;
import android.widget.EditText;
import android.widget.LinearLayout;
import android.widget.TextView;

/**
 * The screens' form elements: a label above a text field, a button. Every field has a fixed id (unique in
 * its screen; small numbers, never the 0x7f... of the app's resources): the framework keeps a
 * field's typed text across the screen's recreation only for a view with an id, and the same id
 * each time (View.generateViewId() would not be).
 */
final class Forms {
    private Forms() {
    }

    /** Adds a label and a text field with id {@code id} holding {@code value} to {@code form}; returns the field. */
    static EditText field(Context context, LinearLayout form, int id, String label, String value, int inputType) {
        TextView l = new TextView(context);
        l.setText(label);
        form.addView(l);
        EditText e = new EditText(context);
        e.setId(id);
        e.setInputType(inputType);
        e.setText(value);
        form.addView(e);
        return e;
    }

    /** Adds a button labelled {@code label} that runs {@code action} on the UI thread to {@code form}. */
    static Button button(Context context, LinearLayout form, String label, final Runnable action) {
        Button b = new Button(context);
        b.setText(label);
        b.setOnClickListener(new View.OnClickListener() {
            @Override
            public void onClick(View v) {
                action.run();
            }
        });
        form.addView(b);
        return b;
    }
}
