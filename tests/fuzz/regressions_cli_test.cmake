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
# tile_layout/issue19-col-overflow.csv (issue 19.1) is fixed on another branch: add
#   refuses_all(tile_layout ${WORK}/positions.csv stitch --layout @FILE@ --overlap 20 -o ${WORK}/positions.csv)
# here when that fix is merged; until then fvm stitch crashes on it.
# batch/number-overflow.json (found by batch_fuzz): nlohmann::json throws out_of_range, not parse_error, for
# 11E15555555; artefacts/io/batch.cc catches parse_error only, so fvm prints the library's message without the
# file. Once batch.cc catches nlohmann::json::exception, add (the input copied as batch.json of a batch dir)
#   a check that fvm calibrate on that directory exits 1 naming batch.json.
