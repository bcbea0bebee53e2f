# fvm uncertainty as a user runs it: the published 75-point mesh (5 x 5 x 3 at 100 mm) with tracker noise and a
# noise-free validation mesh; the JSON contract; the same result for one and two threads; the report; bad input
# that writes nothing.
# Variables: FVM (the executable), SAMPLES (the bundled samples), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

run(0 simulate tracker --machine 400x400x200 --points mesh:100,100,100 --tool 0,0,100 --pose 900,-900,400,0,0,30
    --validation mesh:100,100,50 --seed 1 -o ${WORK}/plan)
set(common ${WORK}/plan/readings.csv --chain XFYZ --order 2 --tool 0,0,100 --fit-pose --runs 24 --seed 3
    --validate ${WORK}/plan/validation.csv --json)
run(0 uncertainty ${common} --threads 1)
set(one "${OUT}")
run(0 uncertainty ${common} --threads 2 --report ${WORK}/report)
set(two "${OUT}")

expect_json_keys("fvm uncertainty" "${one}" runs seconds final_mean_um/mean final_mean_um/sd validation_mean_um/mean
                 validation_mean_um/sd points/0/id points/0/U95_um budget/u_cal_um budget/u_p_um budget/u_b_um
                 budget/u_w_um budget/U_um budget/k)
string(JSON runs GET "${one}" runs)
string(JSON first_id GET "${one}" points 0 id)
string(JSON n_points LENGTH "${one}" points)
if(NOT runs EQUAL 24 OR NOT first_id STREQUAL "P0001" OR NOT n_points EQUAL 200)  # 75 readings + 125 validation points
  message(FATAL_ERROR "runs ${runs}, first point ${first_id}, ${n_points} points")
endif()
# The spread is the tracker noise's: 24 urad at about 1.3 m is some 30 um across the beam; the runs' final mean error
# must scatter by a few um, not zero and not tens.
string(JSON sd GET "${one}" final_mean_um sd)
string(JSON u95 GET "${one}" points 0 U95_um)
expect_near("final mean sd (um)" "${sd}" 3 2.5)
expect_near("U95 of P0001 (um)" "${u95}" 30 25)
string(JSON k GET "${one}" budget k)
string(JSON big_u GET "${one}" budget U_um)
string(JSON u_p GET "${one}" budget u_p_um)
scaled("${big_u}" 3 U3)
scaled("${u_p}" 3 P3)
math(EXPR twice "2 * ${P3}")
if(NOT k EQUAL 2 OR U3 LESS twice)
  message(FATAL_ERROR "budget: k ${k}, U ${big_u} um below 2 u_p (${u_p} um)")
endif()

# Bit-identical for any thread count: everything but the wall time.
string(JSON one REMOVE "${one}" seconds)
string(JSON two REMOVE "${two}" seconds)
if(NOT one STREQUAL two)
  message(FATAL_ERROR "--threads 1 and --threads 2 differ:\n${one}\n----\n${two}")
endif()

expect_files("fvm uncertainty --report" ${WORK}/report index.html distribution.svg u95_map.svg points.csv runs.csv)
file(STRINGS ${WORK}/report/runs.csv run_rows)
list(LENGTH run_rows n_rows)
if(NOT n_rows EQUAL 25)
  message(FATAL_ERROR "runs.csv has ${n_rows} lines, expected a header and 24 runs")
endif()

# Tracker placement: a 2 x 2 x 2 grid of a box beside the machine plus the readings' own position, ranked by
# covariance propagation, the best confirmed by the Monte Carlo; the best is no worse than the current position.
run(0 uncertainty ${WORK}/plan/readings.csv --order 2 --tool 0,0,100 --runs 12 --seed 1 --json
    --place-tracker -200,-1200,0,600,-600,400 --place-steps 2 --place-confirm 1)
string(JSON n_ranked LENGTH "${OUT}" ranked)
string(JSON best GET "${OUT}" ranked 0 predicted_max_U95_um)
string(JSON best_mc GET "${OUT}" ranked 0 monte_carlo_max_U95_um)
math(EXPR last "${n_ranked} - 1")
set(current_predicted "")
foreach(i RANGE ${last})
  string(JSON is_current GET "${OUT}" ranked ${i} current)
  if(is_current)
    string(JSON current_predicted GET "${OUT}" ranked ${i} predicted_max_U95_um)
  endif()
endforeach()
if(NOT n_ranked EQUAL 9 OR current_predicted STREQUAL "" OR best GREATER current_predicted)
  message(FATAL_ERROR "placement: ${n_ranked} ranked, best ${best} um, current ${current_predicted} um:\n${OUT}")
endif()
expect_near("best position: Monte Carlo against covariance propagation (um)" "${best_mc}" "${best}" 8)

run(1 uncertainty ${WORK}/plan/readings.csv --tool 0,0,100 --runs 2 --place-tracker 100,100,0,200,200,100 --place-steps 2)
if(NOT ERR MATCHES "from no position of the box can the tracker see every point")
  message(FATAL_ERROR "a box inside the machine: ${ERR}")
endif()

# The microscope stage: the bundled sample, its centre noise resampled; the runs' validation rms must agree with the
# covariance-based prediction fvm calibrate prints (1.42 um) and the same seed gives the same result.
run(0 uncertainty ${SAMPLES}/bar17 --model 27 --runs 40 --seed 2 --json --threads 2)
string(JSON rms GET "${OUT}" validation_rms_um mean)
string(JSON predicted GET "${OUT}" reference predicted_rms_um)
string(JSON stage_u GET "${OUT}" budget U_um)
expect_near("stage validation rms (um)" "${rms}" "${predicted}" 0.15)
string(JSON stage_one REMOVE "${OUT}" seconds)
run(0 uncertainty ${SAMPLES}/bar17 --model 27 --runs 40 --seed 2 --json --threads 1)
string(JSON stage_two REMOVE "${OUT}" seconds)
if(NOT stage_one STREQUAL stage_two)
  message(FATAL_ERROR "the stage Monte Carlo differs between 1 and 2 threads")
endif()

run(0 uncertainty ${SAMPLES}/bar17 --model 27 --runs 8 --seed 2 --report ${WORK}/stage_report)
expect_files("fvm uncertainty BATCH --report" ${WORK}/stage_report index.html distribution.svg u95_map.svg points.csv
             runs.csv)
run(1 uncertainty ${SAMPLES}/bar17 --runs 2 --validate ${WORK}/plan/validation.csv --report ${WORK}/no)
if(NOT ERR MATCHES "bar17 is a batch directory: --validate")
  message(FATAL_ERROR "--validate with a batch: ${ERR}")
endif()

run(0 uncertainty --help)
if(NOT OUT MATCHES "Example:" OR NOT OUT MATCHES "--runs")
  message(FATAL_ERROR "fvm uncertainty --help:\n${OUT}")
endif()

# Bad input: exit 1 naming the file (and line), nothing written; a bad option is a usage error.
file(WRITE ${WORK}/mixed.csv "id,x,y,z,xt,yt,zt,range\nP1,0,0,0,1,2,3,4\n")
run(1 uncertainty ${WORK}/mixed.csv --runs 2 --report ${WORK}/no)
if(NOT ERR MATCHES "mixed.csv:1:")
  message(FATAL_ERROR "bad readings: ${ERR}")
endif()
file(READ ${WORK}/plan/readings.csv text)
string(REGEX REPLACE "\nP0002," "\nP0001," text "${text}")
file(WRITE ${WORK}/dup.csv "${text}")
run(1 uncertainty ${WORK}/dup.csv --runs 2 --tool 0,0,100 --report ${WORK}/no)
if(NOT ERR MATCHES "dup.csv:[0-9]+:.*P0001")
  message(FATAL_ERROR "duplicate id: ${ERR}")
endif()
run(1 uncertainty ${WORK}/plan/readings.csv --tracker none --runs 2 --tool 0,0,100 --report ${WORK}/no)
run(2 uncertainty ${WORK}/plan/readings.csv --runs 0)
if(EXISTS ${WORK}/no)
  message(FATAL_ERROR "a refused Monte Carlo wrote its report")
endif()
