# cmake -DPROBE=<sanitizer_probe> [-DWITH_PETSC=ON] -P check_sanitizer_probe.cmake
# Runs sanitizer_probe under the environment of the test (the suppressions of a sanitizer
# build): without a leak it passes; each deliberate leak fails with a LeakSanitizer report
# naming the flowire frame that allocated it; a signed overflow fails with a UBSan report.
function(run_probe mode)
  execute_process(COMMAND "${PROBE}" ${mode} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  set(rc "${rc}" PARENT_SCOPE)
  set(log "${out}${err}" PARENT_SCOPE)
endfunction()

run_probe(none)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "sanitizer_probe none (no leak of its own) failed (${rc}): a third-party "
                      "leak is not suppressed or the suppressions are wrong:\n${log}")
endif()
message(STATUS "none: passes")

set(cases new)
if(WITH_PETSC)
  list(APPEND cases petsc)
endif()
foreach(mode IN LISTS cases)
  run_probe(${mode})
  if(rc EQUAL 0)
    message(FATAL_ERROR "sanitizer_probe ${mode}: a deliberate leak passed: the suppressions are too wide\n${log}")
  endif()
  if(NOT log MATCHES "LeakSanitizer: detected memory leaks")
    message(FATAL_ERROR "sanitizer_probe ${mode} failed (${rc}) without a LeakSanitizer report:\n${log}")
  endif()
  if(NOT log MATCHES "in flowire::test::leak_${mode}\\(\\)")
    message(FATAL_ERROR "sanitizer_probe ${mode}: the leak report does not name flowire::test::leak_${mode}:\n${log}")
  endif()
  message(STATUS "${mode}: fails (${rc}) with a leak report naming flowire::test::leak_${mode}")
endforeach()

run_probe(ubsan)
if(rc EQUAL 0 OR NOT log MATCHES "runtime error: signed integer overflow")
  message(FATAL_ERROR "sanitizer_probe ubsan: a signed overflow did not fail with a UBSan report (${rc}):\n${log}")
endif()
message(STATUS "ubsan: fails (${rc}) with a runtime error report")
