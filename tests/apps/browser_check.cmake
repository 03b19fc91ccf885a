# Script mode: write the `arm show` report, then open it in headless Chromium with
# tests/reports/check_report.mjs (fails on console errors or charts that did not render).
file(REMOVE_RECURSE ${OUT_DIR})
execute_process(COMMAND ${FULLARM_EXE} arm show --out ${OUT_DIR} RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "fullarm arm show failed (${rc}): ${err}")
endif()
execute_process(COMMAND ${NODE} ${SOURCE_DIR}/tests/reports/check_report.mjs ${OUT_DIR}/report.html
                        ${OUT_DIR}/screenshot.png --min-charts 3
                WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "browser check failed (${rc}):\n${out}\n${err}")
endif()
