# Hostile-input CLI tests: Database. Against a throwaway server (a superuser, as on the private
# server): reading commands pointed at a database that is not ASRT's, asrt db init, a frame
# already stored (refused before its trace), the --where predicates of
# Testing/Data/hostile/predicates.txt that try to read or write files, run programs, signal other
# sessions or take back the connecting role's rights, a frame row edited to an impossible size, a
# role without CREATEROLE, and two concurrent --replace stores of one frame.
add_test(NAME CLI.Hostile.Database
  COMMAND $<TARGET_FILE:asrtWithThrowawayPostgres>
    "${CMAKE_CURRENT_SOURCE_DIR}/cli-hostile-database.sh"
    ${asrt} ${check} ${expect} "${scenes}" "${work}/hostile-database" "${hostile}")
set_tests_properties(CLI.Hostile.Database PROPERTIES LABELS "cli;store" RUN_SERIAL TRUE
  TIMEOUT 300)
