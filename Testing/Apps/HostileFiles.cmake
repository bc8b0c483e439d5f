# Hostile-input CLI tests: Files. Output files and interrupts (hostile-files.sh has one function
# per case): links planted in the output folder, a file-size limit and a read-only folder (as a
# full disk), a directory where a file of the set goes, stale temporaries, SIGTERM while the scene
# is read from a FIFO, outputs that are FIFOs (written through, refused without a reader, Ctrl-C
# while the reader reads nothing), sockets, links to devices and a device as the prefix (refused),
# show writing through a FIFO, /dev/null and /dev/full, and Ctrl-C while a frame waits for a lock
# to be stored.
set(hostile_files "${CMAKE_CURRENT_SOURCE_DIR}/hostile-files.sh")
foreach (case planted_links file_size_limit read_only_folder directory_in_the_set
    stale_temporaries scene_fifo fifo_outputs refused_outputs)
  add_test(NAME CLI.Files.${case}
    COMMAND ${hostile_files} ${case} ${asrt} ${check} ${expect} "${scenes}" "${work}/files")
  set_tests_properties(CLI.Files.${case} PROPERTIES LABELS cli TIMEOUT 120)
endforeach ()
foreach (case show_through_devices store_interrupt)
  add_test(NAME CLI.Files.${case}
    COMMAND $<TARGET_FILE:asrtWithThrowawayPostgres> ${hostile_files} ${case} ${asrt} ${check}
      ${expect} "${scenes}" "${work}/files")
  set_tests_properties(CLI.Files.${case} PROPERTIES LABELS "cli;store" RUN_SERIAL TRUE
    TIMEOUT 300)
endforeach ()
