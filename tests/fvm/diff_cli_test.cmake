# fvm diff as a user runs it, on the stitching-strategy exports of [Pérez 2019] (samples/stitching-strategies).
# Variables: FVM (the executable), SAMPLES (the samples directory), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

# The one pair of `fvm diff ... --json`: sets A, B, REF_MM, TEST_MM, DIFF_UM.
function(diff_pair)
  run(0 diff ${ARGN} --json)
  string(JSON n LENGTH "${OUT}" pairs)
  if(NOT n EQUAL 1)
    message(FATAL_ERROR "fvm diff ${ARGN}: ${n} pairs, expected 1:\n${OUT}")
  endif()
  foreach(key a b ref_mm test_mm diff_um)
    string(JSON value GET "${OUT}" pairs 0 ${key})
    string(TOUPPER "${key}" name)
    set(${name} "${value}" PARENT_SCOPE)
  endforeach()
endfunction()

set(X ${SAMPLES}/stitching-strategies/x)
set(Y ${SAMPLES}/stitching-strategies/y)

# The numbers computed from the published coordinates (4 decimals of mm), to 1 nm: the 3-D distance by default.
diff_pair(${X}/a.csv ${X}/b.csv --pairs 1:6)
if(NOT A EQUAL 1 OR NOT B EQUAL 6)
  message(FATAL_ERROR "pair ${A}:${B}, expected 1:6")
endif()
expect_near("x a->b ref_mm" ${REF_MM} 20.0080126 0.000001 7)
expect_near("x a->b test_mm" ${TEST_MM} 19.9935556 0.000001 7)
expect_near("x a->b diff_um" ${DIFF_UM} -14.4570 0.001 4)

# Against Table 1: coordinates rounded to 0.05 um move a distance by up to 0.10 um and a difference of two
# distances by 0.20 um; the published distances round to 0.05 um and differences to 0.05 um. So a computed
# distance is within 0.15 um of the table and a computed difference within 0.25 um.
expect_near("x a->b ref_mm vs Table 1" ${REF_MM} 20.0079 0.00015 7)
expect_near("x a->b diff_um vs Table 1" ${DIFF_UM} -14.6 0.25 4)

# The 3-D distance misses Table 2's reference distance by 0.43 um, beyond rounding; the XY-plane distance
# matches every published distance, so [Pérez 2019] measured in the plane: --xy.
diff_pair(${Y}/a.csv ${Y}/b.csv)
expect_near("y a->b 3-D ref_mm" ${REF_MM} 20.0051323 0.000001 7)
diff_pair(${Y}/a.csv ${Y}/b.csv --xy)
if(NOT A EQUAL 1 OR NOT B EQUAL 31)
  message(FATAL_ERROR "default pair ${A}:${B}, expected the first calotte with the other, 1:31")
endif()
expect_near("y a->b xy ref_mm" ${REF_MM} 20.0047517 0.000001 7)
expect_near("y a->b xy diff_um" ${DIFF_UM} -2.2170 0.001 4)

# Tables 1 and 2 whole, with --xy: every distance within 0.15 um, every difference within 0.25 um.
set(x_cases "b 19.9933 -14.6" "c 20.0063 -1.5" "d 19.9989 -8.9" "e 19.9930 -14.8" "f 19.9929 -15.0")
set(y_cases "b 20.0026 -2.2" "c 20.0049 0.2" "d 20.0032 -1.5" "e 20.0020 -2.7" "f 20.0016 -3.1")
foreach(direction x y)
  if(direction STREQUAL "x")
    set(reference 20.0079)
    set(pair 1:6)
  else()
    set(reference 20.0047)
    set(pair 1:31)
  endif()
  foreach(row IN LISTS ${direction}_cases)
    separate_arguments(row)
    list(GET row 0 case)
    list(GET row 1 distance)
    list(GET row 2 difference)
    diff_pair(${SAMPLES}/stitching-strategies/${direction}/a.csv ${SAMPLES}/stitching-strategies/${direction}/${case}.csv
              --pairs ${pair} --xy)
    expect_near("${direction} case ${case} ref_mm" ${REF_MM} ${reference} 0.00015 7)
    expect_near("${direction} case ${case} test_mm" ${TEST_MM} ${distance} 0.00015 7)
    expect_near("${direction} case ${case} diff_um" ${DIFF_UM} ${difference} 0.25 4)
  endforeach()
endforeach()

# The human output, exactly: aligned tables with units in the headers.
run(0 diff ${X}/a.csv ${X}/b.csv)
set(expected "REF   ${X}/a.csv
TEST  ${X}/b.csv

calotte  dx [um]  dy [um]  dz [um]  |d| [um]
      1      0.0     -0.1      2.0       2.0
      6    -14.5     -6.8    -10.3      19.0

distances in 3-D
pair  REF [mm]  TEST [mm]  TEST-REF [um]
 1:6   20.0080    19.9936          -14.5
")
if(NOT OUT STREQUAL expected)
  message(FATAL_ERROR "fvm diff printed:\n${OUT}\nexpected:\n${expected}")
endif()

# The per-calotte JSON: calotte 6 moved by (-14.5, -6.8, -10.3) um.
run(0 diff ${X}/a.csv ${X}/b.csv --json)
string(JSON id GET "${OUT}" calottes 1 id)
string(JSON dx GET "${OUT}" calottes 1 dx_um)
string(JSON dz GET "${OUT}" calottes 1 dz_um)
if(NOT id EQUAL 6)
  message(FATAL_ERROR "second calotte ${id}, expected 6")
endif()
expect_near("calotte 6 dx_um" ${dx} -14.5 0.0001 4)
expect_near("calotte 6 dz_um" ${dz} -10.3 0.0001 4)

# Calottes in only one file: a warning naming them, the common ones compared.
run(0 diff ${Y}/a.csv ${X}/b.csv --json)
if(NOT ERR MATCHES "calotte 31 only in [^\n]*y/a.csv" OR NOT ERR MATCHES "calotte 6 only in [^\n]*x/b.csv")
  message(FATAL_ERROR "no warning about calottes in one file only:\n${ERR}")
endif()
string(JSON n LENGTH "${OUT}" calottes)
string(JSON m LENGTH "${OUT}" pairs)
if(NOT n EQUAL 1 OR NOT m EQUAL 0)
  message(FATAL_ERROR "expected 1 calotte and no pair:\n${OUT}")
endif()

# User errors: exit 1 with a message that names the culprit.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
file(WRITE ${WORK}/nan.csv "id,x,y,z\n1,-154.5487,-115.4767,-50.3624\n6,nan,-115.4371,-50.4457\n")
run(1 diff ${X}/a.csv ${WORK}/nan.csv)
if(NOT ERR MATCHES "nan.csv:3: calotte 6")
  message(FATAL_ERROR "a NaN was not reported with file, line and calotte:\n${ERR}")
endif()
run(1 diff ${X}/a.csv ${X}/b.csv --pairs 1-6)
if(NOT ERR MATCHES "--pairs '1-6'")
  message(FATAL_ERROR "bad --pairs syntax was not named:\n${ERR}")
endif()
run(1 diff ${X}/a.csv ${X}/b.csv --pairs 1:31)
if(NOT ERR MATCHES "calotte 31 is not in")
  message(FATAL_ERROR "a pair with an absent calotte was not named:\n${ERR}")
endif()
run(1 diff ${X}/a.csv ${WORK}/absent.csv)
if(NOT ERR MATCHES "absent.csv")
  message(FATAL_ERROR "a missing file was not named:\n${ERR}")
endif()
file(REMOVE_RECURSE ${WORK})
