# Every .vti, .vtp and .pvd the asrt program writes opens in ParaView's own readers (pvpython)
# with the points its header promises: ParaView shows a file it cannot parse as an empty dataset.
# The series, show and interpolate steps need the store, so it runs against a throwaway server.
# Expects ASRT_PVPYTHON (find_program(ASRT_PVPYTHON pvpython)).
add_test(NAME ParaView.OutputsOpen
  COMMAND $<TARGET_FILE:asrtWithThrowawayPostgres> "${CMAKE_CURRENT_LIST_DIR}/with-own-display.sh"
    "${CMAKE_CURRENT_LIST_DIR}/outputs-open-in-paraview.sh" $<TARGET_FILE:asrt> "${ASRT_PVPYTHON}"
    "${PROJECT_SOURCE_DIR}/Data/scenes" "${CMAKE_CURRENT_BINARY_DIR}/outputs")
set_tests_properties(ParaView.OutputsOpen PROPERTIES
  LABELS "paraview;cli;store" RUN_SERIAL TRUE TIMEOUT 300)
