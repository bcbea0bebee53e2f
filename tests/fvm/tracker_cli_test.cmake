# fvm simulate tracker as a user runs it: the published 96-point plan, its files and row counts, the same bytes for
# the same seed, a truth.json given back as --errors, and bad options.
# Variables: FVM (the executable), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# Rows of a CSV whose ids start with `prefix` (comments and header left out).
function(expect_rows file prefix expected)
  file(STRINGS ${file} rows REGEX "^${prefix}[0-9]+,")
  list(LENGTH rows n)
  if(NOT n EQUAL expected)
    message(FATAL_ERROR "${file}: ${n} rows, expected ${expected}")
  endif()
endfunction()

# The published plan ([IJSIMM 2016] section 5: 2500 x 1500 x 1200 mm, steps 500/500/400 mm = 96 points) with a truth,
# and a noise-free validation mesh of 100 mm (5408 points).
run(0 simulate tracker --machine 2500x1500x1200 --chain XFYZ --points mesh:500,500,400 --tool 0,0,100 -o ${WORK}/a
    --seed 1 --validation mesh:100,100,100)
if(NOT OUT MATCHES "simulated 96 points .* initial volumetric error mean [0-9.]+ um, max [0-9.]+ um.*5408 validation points")
  message(FATAL_ERROR "unexpected summary:\n${OUT}")
endif()
expect_files("fvm simulate tracker" ${WORK}/a points.csv program.nc readings.csv truth.json validation.csv)
expect_rows(${WORK}/a/points.csv P 96)
expect_rows(${WORK}/a/readings.csv P 96)
expect_rows(${WORK}/a/validation.csv V 5408)
file(STRINGS ${WORK}/a/program.nc dwells REGEX "^G4 P6$")
list(LENGTH dwells n)
if(NOT n EQUAL 96)
  message(FATAL_ERROR "program.nc: ${n} dwells, expected 96")
endif()
file(READ ${WORK}/a/readings.csv readings)
if(NOT readings MATCHES "\nid,x,y,z,xt,yt,zt,approach\n" OR NOT readings MATCHES "# chain XFYZ, tool offset 0,0,100 mm")
  message(FATAL_ERROR "readings.csv lacks its header or comments:\n${readings}")
endif()
file(READ ${WORK}/a/truth.json truth)
string(JSON chain GET "${truth}" chain)
string(JSON count GET "${truth}" points count)
string(JSON mean GET "${truth}" mean_error_um)
string(JSON pitch GET "${truth}" terms xTx sine pitch_mm)
if(NOT chain STREQUAL "XFYZ" OR NOT count EQUAL 96 OR NOT mean GREATER 1 OR NOT pitch LESS_EQUAL 40)
  message(FATAL_ERROR "truth.json: chain ${chain}, count ${count}, mean ${mean} um, xTx pitch ${pitch} mm")
endif()

# The same seed, the same bytes; another seed, other readings.
run(0 simulate tracker --machine 2500x1500x1200 --chain XFYZ --points mesh:500,500,400 --tool 0,0,100 -o ${WORK}/b
    --seed 1 --validation mesh:100,100,100)
foreach(name points.csv program.nc readings.csv truth.json validation.csv)
  file(SHA256 ${WORK}/a/${name} first)
  file(SHA256 ${WORK}/b/${name} second)
  if(NOT first STREQUAL second)
    message(FATAL_ERROR "${name} differs between two runs with --seed 1")
  endif()
endforeach()
run(0 simulate tracker -o ${WORK}/c --seed 2)
file(SHA256 ${WORK}/a/readings.csv first)
file(SHA256 ${WORK}/c/readings.csv second)
if(first STREQUAL second)
  message(FATAL_ERROR "--seed 1 and --seed 2 gave the same readings")
endif()

# truth.json given back as --errors (same seed for the noise): the same readings, row for row.
run(0 simulate tracker -o ${WORK}/d --seed 1 --errors ${WORK}/a/truth.json)
file(STRINGS ${WORK}/a/readings.csv rows_a REGEX "^P")
file(STRINGS ${WORK}/d/readings.csv rows_d REGEX "^P")
if(NOT rows_a STREQUAL rows_d)
  message(FATAL_ERROR "--errors truth.json did not reproduce the readings")
endif()

# No truth: the plan alone. A cloud keeps the mesh's count; diagonals give 4 N.
run(0 simulate tracker -o ${WORK}/plan --points cloud:500,500,400)
expect_rows(${WORK}/plan/points.csv P 96)
if(EXISTS ${WORK}/plan/readings.csv OR EXISTS ${WORK}/plan/truth.json)
  message(FATAL_ERROR "readings or truth written without --seed or --errors")
endif()
run(0 simulate tracker -o ${WORK}/diag --points diagonals:11)
expect_rows(${WORK}/diag/points.csv P 44)

# Bad options are usage errors (exit 2); a tracker that cannot see the points is bad input (exit 1). Nothing is
# written either way.
run(2 simulate tracker -o ${WORK}/bad --points mesh:500,500)
if(NOT ERR MATCHES "mesh:500,500")
  message(FATAL_ERROR "bad --points not named:\n${ERR}")
endif()
run(2 simulate tracker -o ${WORK}/bad --machine 2500x1500)
run(2 simulate tracker -o ${WORK}/bad --pose 1,2,3)
run(2 simulate tracker -o ${WORK}/bad --tracker laser)
run(2 simulate tracker -o ${WORK}/bad --validation mesh:100,100,100)
run(1 simulate tracker -o ${WORK}/bad --seed 1 --pose 1250,750,2000,0,0,0)
if(NOT ERR MATCHES "out of the tracker's sight" OR NOT ERR MATCHES "P0002: elevation")
  message(FATAL_ERROR "out-of-sight points not named:\n${ERR}")
endif()
if(EXISTS ${WORK}/bad)
  message(FATAL_ERROR "a failed run wrote ${WORK}/bad")
endif()
