# Script mode: run `fullarm ${ARGS} --out ${OUT_DIR}` (its stdout, stderr and exit code are kept
# in OUT_DIR), then open the report in headless Chromium
# with tests/reports/check_report.mjs (fails on console errors, network requests, or fewer than
# ${MIN_CHARTS} rendered charts) and save a screenshot beside it. Optional: CHECK_ARGS, more
# options of check_report.mjs (a 3D replay's checks; "%OUT_DIR%" stands for OUT_DIR), and
# MAX_REPORT_BYTES, the largest report.html accepted.
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
if(MAX_REPORT_BYTES)
  file(SIZE ${OUT_DIR}/report.html report_bytes)
  message(STATUS "report.html: ${report_bytes} bytes (at most ${MAX_REPORT_BYTES})")
  if(report_bytes GREATER MAX_REPORT_BYTES)
    message(FATAL_ERROR "fullarm ${ARGS}: report.html has ${report_bytes} bytes, more than ${MAX_REPORT_BYTES}")
  endif()
endif()
string(REPLACE "%OUT_DIR%" "${OUT_DIR}" check_args "${CHECK_ARGS}")
separate_arguments(check_args UNIX_COMMAND "${check_args}")
execute_process(COMMAND ${NODE} ${SOURCE_DIR}/tests/reports/check_report.mjs ${OUT_DIR}/report.html
                        ${OUT_DIR}/screenshot.png --min-charts ${MIN_CHARTS} ${check_args}
                WORKING_DIRECTORY ${SOURCE_DIR} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "${out}")
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "browser check failed (${rc}):\n${out}\n${err}")
endif()
