# Hostile-input CLI tests: Inputs.
