# Hostile-input CLI tests: Files.
