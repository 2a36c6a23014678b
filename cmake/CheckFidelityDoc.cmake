# ctest fidelity_doc_is_current: docs/fidelity.md is what nonbloppy_fidelity writes now.
# The tool is deterministic (same numbers on every run, thread count and machine), so any
# difference is a change to the pipeline or to the tool's text that was not regenerated
# (dcd0cf4 edited a line of the document by hand and not in tests/bench/fidelity.cc).
#   cmake -DTOOL=<nonbloppy_fidelity> -DDOC=<docs/fidelity.md> -DOUT=<scratch file> -P CheckFidelityDoc.cmake
execute_process(COMMAND "${TOOL}" --output "${OUT}" RESULT_VARIABLE status OUTPUT_QUIET ERROR_VARIABLE errors)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "nonbloppy_fidelity --output ${OUT} failed (${status}): ${errors}")
endif()
file(READ "${OUT}" generated)
file(READ "${DOC}" committed)
# The document names the command that made it, with its output path.
string(REPLACE "--output ${OUT}" "--output docs/fidelity.md" generated "${generated}")
if(NOT generated STREQUAL committed)
  file(WRITE "${OUT}" "${generated}")
  execute_process(COMMAND diff "${DOC}" "${OUT}" OUTPUT_VARIABLE differences)
  string(SUBSTRING "${differences}" 0 3000 differences)
  message(FATAL_ERROR "docs/fidelity.md (<) differs from what nonbloppy_fidelity writes (>):\n${differences}\n"
                      "regenerate it: build/nonbloppy_fidelity --output docs/fidelity.md")
endif()
