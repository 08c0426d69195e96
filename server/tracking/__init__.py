"""Per-device tracking: motion filter, ID evidence across frames, beacon hand-over."""
