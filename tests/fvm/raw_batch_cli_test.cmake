# fvm simulate fvm-batch --surfaces x3p and fvm calibrate on it (issue 29 part 5): the stage model recovered from
# the surfaces, through the calotte search and sphere fits of fvm fit, validates within 1.2x of the centre exports
# the same simulation wrote; two exports of a placement that do not show the same calottes are refused, nothing
# written.
include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

# Coarse pixels (0.1 mm: ~290 points per calotte) and four validation placements keep it to seconds; 3 um of
# height noise gives centres about as noisy as the CSV route's 0.5 um.
run(0 simulate fvm-batch -o "${WORK}/raw" --seed 5 --validation-placements 4 --surfaces x3p --surface-pixel-mm 0.1
    --surface-noise-um 3)
foreach(f raw/id-x.stitched.x3p raw/id-x.free.x3p raw/val-04.free.x3p raw/batch.json raw/truth.json
          raw/centres/id-x.stitched.csv raw/centres/batch.json)
  if(NOT EXISTS "${WORK}/${f}")
    message(FATAL_ERROR "fvm simulate fvm-batch --surfaces x3p wrote no ${f}")
  endif()
endforeach()
if(EXISTS "${WORK}/raw/id-x.stitched.csv")
  message(FATAL_ERROR "fvm simulate fvm-batch --surfaces x3p wrote centre exports beside the surfaces")
endif()

# The raw route: every export gives the bar's 17 calottes; the centres are written where asked, as a CSV batch.
run(0 calibrate "${WORK}/raw" --model 27 --json --centres-dir "${WORK}/found")
set(raw_json "${OUT}")
string(JSON exports LENGTH "${raw_json}" raw_exports exports)
if(NOT exports EQUAL 14)
  message(FATAL_ERROR "calibrate on 7 placements of surfaces reported ${exports} exports, expected 14")
endif()
math(EXPR last "${exports} - 1")
foreach(i RANGE ${last})
  string(JSON n GET "${raw_json}" raw_exports exports ${i} calottes)
  if(NOT n EQUAL 17)
    string(JSON f GET "${raw_json}" raw_exports exports ${i} file)
    message(FATAL_ERROR "${f}: ${n} calottes found, expected the bar's 17")
  endif()
endforeach()
string(JSON raw_rms GET "${raw_json}" validation rigid rms_um)
file(GLOB written "${WORK}/found/*.csv")
list(LENGTH written written_count)
if(NOT written_count EQUAL 14 OR NOT EXISTS "${WORK}/found/batch.json")
  message(FATAL_ERROR "calibrate --centres-dir wrote ${written_count} centre exports, expected 14 and batch.json")
endif()
file(GLOB in_batch "${WORK}/raw/*.csv")
if(in_batch)
  message(FATAL_ERROR "calibrate wrote into the user's batch: ${in_batch}")
endif()

# The centre-CSV route of the same simulation, and the centres found calibrated again as a CSV batch.
run(0 calibrate "${WORK}/raw/centres" --model 27 --json)
string(JSON csv_rms GET "${OUT}" validation rigid rms_um)
run(0 calibrate "${WORK}/found" --model 27 --json)
string(JSON found_rms GET "${OUT}" validation rigid rms_um)
expect_near("rigid validation rms of the centres found, calibrated as a CSV batch" "${found_rms}" "${raw_rms}" 0.001)
message(STATUS "validation rigid rms: raw surfaces ${raw_rms} um, centre exports ${csv_rms} um")
scaled("${raw_rms}" 4 raw_scaled)
scaled("${csv_rms}" 4 csv_scaled)
math(EXPR limit "${csv_scaled} * 12 / 10")
if(raw_scaled GREATER limit)
  message(FATAL_ERROR "raw route validates at ${raw_rms} um rms, more than 1.2 x the centre route's ${csv_rms} um")
endif()

# Refusal: the stitching-free export of another placement in id-x's place: every calotte lies elsewhere.
file(MAKE_DIRECTORY "${WORK}/swapped")
file(GLOB surfaces "${WORK}/raw/*.x3p" "${WORK}/raw/batch.json")
file(COPY ${surfaces} DESTINATION "${WORK}/swapped")
file(COPY_FILE "${WORK}/raw/val-01.free.x3p" "${WORK}/swapped/id-x.free.x3p")
execute_process(COMMAND ${FVM} calibrate "${WORK}/swapped" --model 27 -o "${WORK}/swapped.json" --report "${WORK}/report"
                RESULT_VARIABLE code ERROR_VARIABLE err OUTPUT_VARIABLE out)
if(NOT code EQUAL 1 OR NOT err MATCHES "placement id-x: calotte 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17 numbered differently")
  message(FATAL_ERROR "a placement whose exports show different calottes: exit ${code}, expected 1 naming the ids:\n${err}")
endif()
if(EXISTS "${WORK}/swapped.json" OR EXISTS "${WORK}/report" OR EXISTS "${WORK}/swapped.centres")
  message(FATAL_ERROR "a refused raw batch left output behind")
endif()
# The centres never go into the batch of surfaces itself.
fails_naming("would go into the batch of surfaces itself" calibrate "${WORK}/raw" --model 27 --centres-dir "${WORK}/raw")
# A placement with one export only.
file(REMOVE "${WORK}/swapped/id-x.free.x3p")
fails_naming("id-x.stitched.x3p: has no partner" calibrate "${WORK}/swapped" --model 27)
