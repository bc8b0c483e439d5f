# Hostile-input CLI tests: Frames.
