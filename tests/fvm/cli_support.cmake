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

# CMake has integer arithmetic only: a plain decimal string becomes an integer in units of 10^-digits. Digits
# beyond are cut, not rounded: string(JSON) re-prints numbers with 17 significant digits (-14.457000000000001).
function(scaled value digits result)
  if(NOT value MATCHES "^(-?)([0-9]+)(\\.([0-9]*))?$")
    message(FATAL_ERROR "'${value}' is not a plain decimal number")
  endif()
  set(sign "${CMAKE_MATCH_1}")  # before the next regex overwrites CMAKE_MATCH_*
  set(fraction "${CMAKE_MATCH_4}0000000000")
  string(SUBSTRING "${fraction}" 0 ${digits} fraction)
  # Leading zeros off (REGEX REPLACE would re-anchor '^' after each match: 05068 -> 568).
  string(REGEX MATCH "[1-9][0-9]*$" digits_only "${CMAKE_MATCH_2}${fraction}")
  if(digits_only STREQUAL "")
    set(digits_only 0)
  endif()
  set(${result} "${sign}${digits_only}" PARENT_SCOPE)
endfunction()

# |actual - expected| <= tolerance, all decimal strings, compared at `digits` decimals (default 4).
function(expect_near what actual expected tolerance)
  set(digits 4)
  if(ARGC GREATER 4)
    set(digits ${ARGV4})
  endif()
  scaled("${actual}" ${digits} a)
  scaled("${expected}" ${digits} e)
  scaled("${tolerance}" ${digits} t)
  math(EXPR deviation "${a} - (${e})")
  if(deviation LESS 0)
    math(EXPR deviation "-(${deviation})")
  endif()
  if(deviation GREATER t)
    message(FATAL_ERROR "${what} = ${actual}, expected ${expected} +- ${tolerance}")
  endif()
endfunction()

# Every key path (members joined by '/', array indices as numbers: "points/0/id") is present in the JSON text.
function(expect_json_keys what json)
  foreach(path IN LISTS ARGN)
    string(REPLACE "/" ";" keys "${path}")
    string(JSON ignored ERROR_VARIABLE missing GET "${json}" ${keys})
    if(missing)
      message(FATAL_ERROR "${what} --json has no '${path}':\n${json}")
    endif()
  endforeach()
endfunction()

# Every named file exists in `dir`: what a command (`what`) promised to write.
function(expect_files what dir)
  foreach(name IN LISTS ARGN)
    if(NOT EXISTS ${dir}/${name})
      message(FATAL_ERROR "${what} wrote no ${name}")
    endif()
  endforeach()
endfunction()
