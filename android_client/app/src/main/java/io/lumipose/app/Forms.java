package io.lumipose.app;

import android.content.Context;
import android.widget.EditText;
import android.widget.LinearLayout;
import android.widget.TextView;

/** The screens' one form element: a label above a text field. */
final class Forms {
    private Forms() {
    }

    /** Adds a label and a text field holding {@code value} to {@code form}; returns the field. */
    static EditText field(Context context, LinearLayout form, String label, String value, int inputType) {
        TextView l = new TextView(context);
        l.setText(label);
        form.addView(l);
        EditText e = new EditText(context);
        e.setInputType(inputType);
        e.setText(value);
        form.addView(e);
        return e;
    }
}
