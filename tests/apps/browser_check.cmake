# Script mode: run `fullarm ${ARGS} --out ${OUT_DIR}` (its stdout, stderr and exit code are kept
# in OUT_DIR), then open the report in headless Chromium
# with tests/reports/check_report.mjs (fails on console errors, network requests, or fewer than
# ${MIN_CHARTS} rendered charts) and save a screenshot beside it.
file(REMOVE_RECURSE ${OUT_DIR})
separate_arguments(args UNIX_COMMAND "${ARGS}")
execute_process(COMMAND ${FULLARM_EXE} ${args} --out ${OUT_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE stdout
                ERROR_VARIABLE err)
# Kept for tests that check this run's output (the demo runs once; tests/apps/demo_run_test.cpp).
file(WRITE ${OUT_DIR}/fullarm_stdout.txt "${stdout}")
file(WRITE ${OUT_DIR}/fullarm_stderr.txt "${err}")
file(WRITE ${OUT_DIR}/fullarm_exit_code.txt "${rc}")
# Exit code 1 is a failing verdict (the report is still written): accepted when ALLOW_FAIL_VERDICT.
if(NOT rc EQUAL 0 AND NOT (ALLOW_FAIL_VERDICT AND rc EQUAL 1))
  message(FATAL_ERROR "fullarm ${ARGS} failed (${rc}): ${err}")
endif()
execute_process(COMMAND ${NODE} ${SOURCE_DIR}/tests/reports/check_report.mjs ${OUT_DIR}/report.html
                        ${OUT_DIR}/screenshot.png --min-charts ${MIN_CHARTS}
                WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "browser check failed (${rc}):\n${out}\n${err}")
endif()
