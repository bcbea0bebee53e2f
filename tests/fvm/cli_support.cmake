# Shared by the CLI test scripts: run fvm with arguments, expect an exit code, keep stdout in OUT and stderr in ERR.
function(run expected_code)
  execute_process(COMMAND ${FVM} ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL expected_code)
    message(FATAL_ERROR "fvm ${ARGN}: exit ${code}, expected ${expected_code}\n${out}\n${err}")
  endif()
  set(OUT "${out}" PARENT_SCOPE)
  set(ERR "${err}" PARENT_SCOPE)
endfunction()

# Expect a failure: non-zero exit, and stderr names `what`.
function(fails_naming what)
  execute_process(COMMAND ${FVM} ${ARGN} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(code EQUAL 0 OR NOT err MATCHES "${what}")
    message(FATAL_ERROR "fvm ${ARGN}: exit ${code}; expected a failure naming '${what}', got:\n${err}")
  endif()
endfunction()
