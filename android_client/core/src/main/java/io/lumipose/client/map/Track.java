package io.lumipose.client.map;

import java.util.ArrayDeque;
import java.util.ArrayList;
import java.util.List;

/** The most recent positions (x, y, z in m), oldest first, bounded so the live view stays light. */
public final class Track {
    private final int capacity;
    private final ArrayDeque<double[]> points = new ArrayDeque<double[]>();

    public Track(int capacity) {
        if (capacity < 1) {
            throw new IllegalArgumentException("capacity must be >= 1, got " + capacity);
        }
        this.capacity = capacity;
    }

    public synchronized void add(double[] positionM) {
        if (positionM == null || positionM.length != 3) {
            throw new IllegalArgumentException("position must hold 3 numbers");
        }
        if (points.size() == capacity) {
            points.removeFirst();
        }
        points.addLast(positionM.clone());
    }

    public synchronized List<double[]> snapshot() {
        List<double[]> out = new ArrayList<double[]>(points.size());
        for (double[] p : points) {
            out.add(p.clone());
        }
        return out;
    }

    public synchronized void clear() {
        points.clear();
    }
}
