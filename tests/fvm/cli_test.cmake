# Checks the command line as a user sees it: honest help, version, and exit codes.
include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

set(COMMANDS calibrate correct compare diff diagnose simulate info fit focus tiles stitch verify multilaterate uncertainty testpiece)
run(0 --help)
foreach(cmd ${COMMANDS})
  if(NOT OUT MATCHES "${cmd}")
    message(FATAL_ERROR "fvm --help does not list '${cmd}':\n${OUT}")
  endif()
endforeach()

run(0 --version)
# The release and the commit it was built from ("unknown" outside a git checkout).
if(NOT "${OUT}${ERR}" MATCHES "^fvm [0-9]+\\.[0-9]+\\.[0-9]+ \\(commit ([0-9a-f]+(-dirty)?|unknown)\\)\n?$")
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

# Usage errors (unknown command or option, missing or invalid argument, option without its value) all exit 2,
# name the command, point to its --help, and never print the binary's full path.
get_filename_component(fvm_dir "${FVM}" DIRECTORY)
foreach(case
    "no-such-command"
    "calibrate"
    "calibrate ${SAMPLES}/bar17 --model 28"
    "calibrate ${SAMPLES}/bar17 --model"
    "tiles plan --no-such-option"
    "tiles"
    "stitch --layout x.csv --overlap 20 -o p.csv --threads -1")
  separate_arguments(arguments UNIX_COMMAND "${case}")
  run(2 ${arguments})
  string(FIND "${ERR}${OUT}" "${fvm_dir}" at)
  if(NOT at EQUAL -1)
    message(FATAL_ERROR "fvm ${case}: the message shows the binary's path:\n${ERR}")
  endif()
  list(GET arguments 0 command)
  if(command STREQUAL "no-such-command")
    set(command "")
  else()
    set(command " ${command}")
  endif()
  if(NOT ERR MATCHES "^fvm${command}[ :]" OR NOT ERR MATCHES "Run 'fvm${command}[a-z ]* --help'")
    message(FATAL_ERROR "fvm ${case}: expected 'fvm${command}...: <message>' and a --help hint, got:\n${ERR}")
  endif()
endforeach()

# fvm --help: one line per command (summary only: the paragraphs are in each command's own --help), and the exit
# codes in the footer.
run(0 --help)
string(REGEX MATCH "\nSubcommands:\n([^\n]+\n)+" block "${OUT}")
string(REGEX REPLACE "^\nSubcommands:\n" "" block "${block}")
# Count line ends, not list items: the "[not built yet]" brackets would group CMake list items.
string(REGEX MATCHALL "\n" line_ends "${block}")
list(LENGTH line_ends lines)
list(LENGTH COMMANDS expected_lines)
if(NOT lines EQUAL expected_lines)
  message(FATAL_ERROR "fvm --help: ${lines} lines for ${expected_lines} commands; expected one line each:\n${OUT}")
endif()
foreach(cmd ${COMMANDS})
  if(NOT block MATCHES "(^|\n)  ${cmd} +[^ \n]")
    message(FATAL_ERROR "fvm --help: no one-line summary for '${cmd}':\n${block}")
  endif()
endforeach()
foreach(code "0  done" "1  bad input" "2  usage" "3  did not converge")
  if(NOT OUT MATCHES "Exit codes:.*\n  ${code}")
    message(FATAL_ERROR "fvm --help does not document exit code '${code}':\n${OUT}")
  endif()
endforeach()

# fvm --help, every built command and every subcommand its --help lists (the list read from the help, so that a new
# one cannot go without) end their --help with an example; the summary heads a command's description.
run(0 --help)
if(NOT OUT MATCHES "\nExample[^\n]*:\n  fvm [a-z]")
  message(FATAL_ERROR "fvm --help has no example:\n${OUT}")
endif()
set(with_subcommands ${COMMANDS})
foreach(cmd ${COMMANDS})
  run(0 ${cmd} --help)
  string(REGEX MATCH "\nSubcommands:\n([^\n]+\n)+" block "${OUT}")
  string(REGEX MATCHALL "\n  [a-z][a-z-]*" names "${block}")
  foreach(name ${names})
    string(STRIP "${name}" name)
    list(APPEND with_subcommands "${cmd} ${name}")
  endforeach()
endforeach()
foreach(expected "simulate fvm-batch" "simulate scan" "simulate tracker" "simulate testpiece" "tiles plan"
    "tiles synthesize" "tiles simulate" "testpiece design" "testpiece verify")
  list(FIND with_subcommands "${expected}" found)  # (a -P script runs under old policies: no IN_LIST)
  if(found EQUAL -1)
    message(FATAL_ERROR "the subcommands read from --help lack '${expected}': ${with_subcommands}")
  endif()
endforeach()
foreach(cmd ${with_subcommands})
  separate_arguments(words UNIX_COMMAND "${cmd}")
  run(0 ${words} --help)
  if(NOT OUT MATCHES "Example[^\n]*:\n  fvm |Example: fvm ")
    message(FATAL_ERROR "fvm ${cmd} --help has no example:\n${OUT}")
  endif()
  if(NOT OUT MATCHES "^[^\n]+\n(\n[^\n]+\n)?Usage: fvm ${cmd} ")
    message(FATAL_ERROR "fvm ${cmd} --help: expected the one-line summary, then 'Usage: fvm ${cmd}':\n${OUT}")
  endif()
endforeach()

# One spelling per concept in --help; the old spellings still work, hidden, and give the same result.
run(0 tiles plan --help)
if(NOT OUT MATCHES "--radius-mm" OR NOT OUT MATCHES "--tile-px" OR NOT OUT MATCHES "--fov-mm")
  message(FATAL_ERROR "fvm tiles plan --help lacks the unit-named options:\n${OUT}")
endif()
if(OUT MATCHES "--radius[ ,]" OR OUT MATCHES "--tile-pixels" OR OUT MATCHES "--fov[ ,]")
  message(FATAL_ERROR "fvm tiles plan --help shows an old spelling:\n${OUT}")
endif()
set(plan tiles plan --lens 10x --artefact grid6x6 --overlap 13 --json)
run(0 ${plan} --radius-mm 0.8 --tile-px 2048x2048 --fov-mm 1.5)
set(new_spelling "${OUT}")
run(0 ${plan} --radius 0.8 --tile-pixels 2048x2048 --fov 1.5)
if(NOT OUT STREQUAL new_spelling)
  message(FATAL_ERROR "old and new spellings differ:\n${OUT}\n---\n${new_spelling}")
endif()
string(JSON fov GET "${OUT}" fov_mm)
string(JSON bytes GET "${OUT}" stitched bytes)
run(0 ${plan})
string(JSON default_bytes GET "${OUT}" stitched bytes)
if(NOT fov STREQUAL "1.5" OR bytes STREQUAL default_bytes)
  message(FATAL_ERROR "--fov 1.5 / --tile-pixels 2048x2048 were not applied: fov ${fov}, bytes ${bytes}")
endif()
run(0 info --help)
if(NOT OUT MATCHES "--pixel-mm" OR OUT MATCHES "--pixel-size|--dx-mm|--z-scale[ ,]")
  message(FATAL_ERROR "fvm info --help: expected --pixel-mm and no old spelling:\n${OUT}")
endif()

# --threads and --quiet belong to the whole program and may come before or after the command.
run(0 --threads 1 --quiet tiles plan --lens 5x --region 0,0,10,10 --overlap 20)
run(0 tiles plan --lens 5x --region 0,0,10,10 --overlap 20 --threads 1 -q)

# An option value the tile size cannot be is a usage error (exit 2) that names the option and the value.
run(2 tiles plan --lens 5x --region 0,0,10,10 --tile-px 1024xABC)
if(NOT ERR MATCHES "--tile-px '1024xABC'")
  message(FATAL_ERROR "--tile-px 1024xABC: the message does not name the option:\n${ERR}")
endif()
