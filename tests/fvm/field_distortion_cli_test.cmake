# Issue 43 as a user runs it: `fvm diagnose --scan` names field_distortion on simulated scans through a known field
# and nothing on the same scans without it; `fvm stitch --distortion --report DIR` writes the page and its plots, the
# field's numbers as --json has them; bad combinations refused naming the option. Variables: FVM, WORK.

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# 1. diagnose on scans: k1 = 2 px is 2 sqrt(2) 2 = 5.66 px at a tile's corners.
foreach(d 2 0)
  run(0 simulate scan -o ${WORK}/s${d} --seed 2 --tile-px 256 --length-mm 20 --validation 1 --distortion ${d})
  file(READ ${WORK}/s${d}/truth.json truth)
  string(JSON pixel GET "${truth}" pixel_mm)
  run(0 diagnose --scan ${WORK}/s${d}/row.csv --scan ${WORK}/s${d}/column.csv --scan ${WORK}/s${d}/diagonal.csv
      --pixel-mm ${pixel} --json)
  string(JSON effect GET "${OUT}" effect)
  string(JSON before GET "${OUT}" before rms_px)
  string(JSON after GET "${OUT}" after rms_px)
  if(d EQUAL 2)
    string(JSON size GET "${OUT}" size value)
    if(NOT effect STREQUAL "field_distortion")
      message(FATAL_ERROR "diagnose --scan, k1 = 2 px: effect '${effect}', expected field_distortion:\n${OUT}")
    endif()
    expect_near("largest displacement (px)" "${size}" 5.657 0.2)
    run(0 diagnose --scan ${WORK}/s2/row.csv --scan ${WORK}/s2/column.csv --scan ${WORK}/s2/diagonal.csv --pixel-mm ${pixel})
    if(NOT OUT MATCHES "effect: field_distortion \\(order 3\\), largest displacement 5\\.[5-7][0-9] px")
      message(FATAL_ERROR "diagnose --scan text:\n${OUT}")
    endif()
  elseif(NOT effect STREQUAL "NOTFOUND" AND NOT effect STREQUAL "null" AND NOT effect STREQUAL "")
    message(FATAL_ERROR "diagnose --scan without a field named '${effect}':\n${OUT}")
  endif()
endforeach()
fails_naming("--pixel-mm" diagnose --scan ${WORK}/s0/row.csv)
fails_naming("BATCH" diagnose ${WORK}/s0 --scan ${WORK}/s0/row.csv --pixel-mm 0.01)
fails_naming("--overlap" diagnose --layout ${WORK}/s0/row.csv)
fails_naming("--report" diagnose --scan ${WORK}/s0/row.csv --scan ${WORK}/s0/column.csv --pixel-mm 0.01 --report ${WORK}/r)
# The batch's stage-model options have nothing to act on in the tiles' test (positions free, the field's model is
# --order), and the tiles' options nothing in a batch: refused naming the option, not ignored.
fails_naming("--model" diagnose --scan ${WORK}/s0/row.csv --scan ${WORK}/s0/column.csv --pixel-mm 0.01 --model 27)
fails_naming("--terms" diagnose --layout ${WORK}/s0/row.csv --overlap 10 --terms xTx:1)
fails_naming("--stitched-frame" diagnose --layout ${WORK}/s0/row.csv --overlap 10 --stitched-frame rotated)
fails_naming("--loss-scale-um" diagnose --scan ${WORK}/s0/row.csv --pixel-mm 0.01 --loss-scale-um 5)
fails_naming("--order" diagnose ${WORK}/s0 --order 4)
fails_naming("--pixel-mm" diagnose ${WORK}/s0 --pixel-mm 0.01)

# 2. stitch --report with a field: the page, both plots, the terms with u as --json has them.
run(0 tiles synthesize -o ${WORK}/set --rows 3 --cols 3 --bits 8 --seed 4)
run(0 stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/set/p.csv --pixel-mm 0.001 --distortion
    --report ${WORK}/report --json)
expect_files("fvm stitch --report" ${WORK}/report index.html positions.svg field.svg)
file(READ ${WORK}/report/index.html page)
string(JSON name GET "${OUT}" distortion terms 0 name)
string(JSON before GET "${OUT}" distortion overlap_ncc_before)
string(JSON after GET "${OUT}" distortion overlap_ncc_after)
foreach(heading "Tiles and pairs" "Field distortion terms" "Neighbour pairs" "Loop misclosures" "Tile positions")
  if(NOT page MATCHES "<h2>${heading}</h2>")
    message(FATAL_ERROR "stitch report: no '${heading}' section")
  endif()
endforeach()
if(NOT page MATCHES "<td>${name}</td>")
  message(FATAL_ERROR "stitch report: term ${name} missing")
endif()
# Without a field: no field plot, and the text names the report.
run(0 stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/set/p.csv --report ${WORK}/rigid)
expect_files("fvm stitch --report (rigid)" ${WORK}/rigid index.html positions.svg)
if(EXISTS ${WORK}/rigid/field.svg OR NOT OUT MATCHES "report to ${WORK}/rigid/index.html")
  message(FATAL_ERROR "stitch --report without a field:\n${OUT}")
endif()
