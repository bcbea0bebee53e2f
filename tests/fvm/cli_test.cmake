# Checks the command line as a user sees it: honest help, version, and exit codes.
include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

set(COMMANDS calibrate correct compare diff diagnose simulate info fit focus tiles stitch verify uncertainty)
run(0 --help)
foreach(cmd ${COMMANDS})
  if(NOT OUT MATCHES "${cmd}")
    message(FATAL_ERROR "fvm --help does not list '${cmd}':\n${OUT}")
  endif()
endforeach()

run(0 --version)
if(NOT "${OUT}${ERR}" MATCHES "^fvm [0-9]+\\.[0-9]+\\.[0-9]+")
  message(FATAL_ERROR "fvm --version printed: ${OUT}")
endif()

# A command that is not built yet says so in --help, and when run it says so again and exits 2.
execute_process(COMMAND ${FVM} --help OUTPUT_VARIABLE help)
foreach(cmd ${COMMANDS})
  string(REGEX MATCH "\n  ${cmd} [^\n]*" line "${help}")
  if(line MATCHES "not built yet")
    run(2 ${cmd})
    if(NOT ERR MATCHES "not built yet")
      message(FATAL_ERROR "fvm ${cmd} exited 2 without saying it is not built: ${ERR}")
    endif()
  endif()
endforeach()

# A usage error names the problem and fails.
execute_process(COMMAND ${FVM} no-such-command RESULT_VARIABLE code ERROR_VARIABLE err)
if(code EQUAL 0 OR NOT err MATCHES "no-such-command|subcommand")
  message(FATAL_ERROR "fvm no-such-command: exit ${code}: ${err}")
endif()
