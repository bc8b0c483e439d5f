# Hostile-input CLI tests: Database.
