# Every regression input under REGRESSIONS/<reader>/ through the command that reads it, as a user runs it: exit
# 1, a message naming the file, no crash, nothing written. Expects FVM, WORK, REGRESSIONS and SUPPORT
# (tests/fvm/cli_support.cmake).
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})
include(${SUPPORT})

# A reader's inputs: fvm <args...> with @FILE@ replaced by the input; `output` must not exist afterwards.
function(refuses_all reader output)
  file(GLOB inputs ${REGRESSIONS}/${reader}/*)
  list(LENGTH inputs count)
  if(count EQUAL 0)
    message(FATAL_ERROR "no regression inputs in ${REGRESSIONS}/${reader}")
  endif()
  foreach(input IN LISTS inputs)
    get_filename_component(file_name ${input} NAME)
    # A copy in WORK: the file name in the message is then the copy's, and nothing can write beside the source.
    file(COPY ${input} DESTINATION ${WORK})
    string(REPLACE "@FILE@" "${WORK}/${file_name}" arguments "${ARGN}")
    run(1 ${arguments})
    if(NOT ERR MATCHES "${file_name}")
      message(FATAL_ERROR "fvm ${arguments}: the message does not name ${file_name}:\n${ERR}")
    endif()
    if(NOT output STREQUAL "" AND EXISTS ${output})
      message(FATAL_ERROR "fvm ${arguments}: wrote ${output} although it failed")
    endif()
    message(STATUS "${reader}/${file_name}: ${ERR}")
  endforeach()
endfunction()

refuses_all(pcd "" info @FILE@)
refuses_all(ply "" info @FILE@)
refuses_all(tile_layout ${WORK}/positions.csv stitch --layout @FILE@ --overlap 20 -o ${WORK}/positions.csv)
refuses_all(height_map_image "" info @FILE@ --pixel-mm 0.001)
refuses_all(tile_image "" info @FILE@ --pixel-mm 0.001)

# batch/number-overflow.json as the batch.json of a batch: nlohmann's out_of_range, not parse_error.
file(MAKE_DIRECTORY ${WORK}/batch)
file(COPY ${REGRESSIONS}/batch/number-overflow.json DESTINATION ${WORK}/batch)
file(RENAME ${WORK}/batch/number-overflow.json ${WORK}/batch/batch.json)
file(WRITE ${WORK}/batch/a.stitched.csv "id,x,y,z\n1,0,0,0\n2,1,0,0\n")
file(WRITE ${WORK}/batch/a.free.csv "id,x,y,z\n1,0,0,0\n2,1,0,0\n")
run(1 calibrate ${WORK}/batch --model 9 -o ${WORK}/cal.json)
if(NOT ERR MATCHES "batch.json" OR EXISTS ${WORK}/cal.json)
  message(FATAL_ERROR "fvm calibrate on a batch.json with a number beyond double:\n${ERR}")
endif()
refuses_all(tracker_readings ${WORK}/machine.json verify @FILE@ --tool 0,0,100 -o ${WORK}/machine.json)
# Multilateration readings and stations through fvm multilaterate (the stations file of the other: a valid one).
file(WRITE ${WORK}/ok-stations.json "{\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": 0, \"z\": 0}, {\"name\": \"B\", \"x\": 1000, \"y\": 0, \"z\": 0}, {\"name\": \"C\", \"x\": 0, \"y\": 1000, \"z\": 0}]}")
file(WRITE ${WORK}/ok-readings.csv "id,station,range\nP1,A,707.1067811865476\nP1,B,948.6832980505138\nP1,C,836.6600265340756\n")
refuses_all(multilateration_readings ${WORK}/points.csv multilaterate @FILE@ --stations ${WORK}/ok-stations.json -o ${WORK}/points.csv)
refuses_all(stations ${WORK}/points.csv multilaterate ${WORK}/ok-readings.csv --stations @FILE@ -o ${WORK}/points.csv)
