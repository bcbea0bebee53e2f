cmake_policy(SET CMP0057 NEW)  # if(IN_LIST)
# The report pictures as a reader sees them (issue 33): every command that writes a report writes it on small
# simulated inputs, then every SVG it holds must (1) render with rsvg-convert to a non-empty PNG and (2) have no text
# over another text and none past the canvas (svg_text_check; tests/fvm/svg_text_boxes.h says what that can see).
# Variables: FVM (the executable), CHECK (svg_text_check), SAMPLES (the bundled samples), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

find_program(RSVG rsvg-convert)
if(NOT RSVG)
  message(FATAL_ERROR "rsvg-convert is missing: install the Debian package 'librsvg2-bin' (run.sh does)")
endif()

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# The stage: calibrate, diagnose, the scan route judged on a batch's placements, the stage Monte Carlo.
run(0 simulate fvm-batch -o ${WORK}/batch --seed 1)
run(0 calibrate ${WORK}/batch --model 27 -o ${WORK}/cal.json --report ${WORK}/calibrate)
run(0 simulate fvm-batch -o ${WORK}/drift --seed 7 --hidden-effect thermal_drift)
run(0 diagnose ${WORK}/drift --model 27 --report ${WORK}/diagnose)
run(0 simulate scan -o ${WORK}/scan --seed 1 --tile-px 128 --length-mm 30 --validation 5)
file(READ ${WORK}/scan/truth.json truth)
string(JSON pixel GET "${truth}" pixel_mm)
run(0 calibrate --scan ${WORK}/scan/row.csv --scan ${WORK}/scan/column.csv --scan ${WORK}/scan/diagonal.csv
    --pixel-mm ${pixel} --model 15 --validate ${WORK}/batch -o ${WORK}/scan_cal.json --report ${WORK}/calibrate_scan)
run(0 uncertainty ${SAMPLES}/bar17 --model 27 --runs 4 --seed 2 --report ${WORK}/uncertainty_stage)
# The machine tool: verify, its Monte Carlo, the test piece.
run(0 simulate tracker --seed 1 --tool 0,0,100 --validation mesh:250,250,200 -o ${WORK}/plan)
run(0 verify ${WORK}/plan/readings.csv --chain XFYZ --order 2 --tool 0,0,100 --validate ${WORK}/plan/validation.csv
    --report ${WORK}/verify)
run(0 uncertainty ${WORK}/plan/readings.csv --chain XFYZ --order 2 --tool 0,0,100 --fit-pose --runs 8 --seed 3
    --validate ${WORK}/plan/validation.csv --report ${WORK}/uncertainty)
run(0 simulate testpiece -o ${WORK}/tp --validation 30,30,30)
run(0 testpiece verify ${WORK}/tp/measured.csv --basis chebyshev --order 2 --nominal ${WORK}/tp/nominal.csv
    --validate ${WORK}/tp/validation.csv --report ${WORK}/testpiece)

# Every page each report's HTML shows is there, so a page that stops being written is not silently unchecked.
set(pages
  calibrate distance_errors error_vectors parameters
  diagnose distance_errors error_vectors parameters steps
  calibrate_scan distance_errors error_vectors parameters
  uncertainty_stage distribution u95_map
  verify error_functions volumetric_errors error_map
  uncertainty distribution u95_map
  testpiece error_functions volumetric_errors error_map)
set(svgs "")
foreach(item IN LISTS pages)
  if(item MATCHES "^(calibrate|diagnose|calibrate_scan|uncertainty_stage|verify|uncertainty|testpiece)$")
    set(report ${item})
    file(GLOB written RELATIVE ${WORK}/${report} ${WORK}/${report}/*.svg)
    file(READ ${WORK}/${report}/index.html page)
    foreach(svg IN LISTS written)
      if(NOT page MATCHES "src=\"${svg}\"")
        message(FATAL_ERROR "${report}/${svg} is written but index.html does not show it")
      endif()
    endforeach()
    continue()
  endif()
  set(svg ${WORK}/${report}/${item}.svg)
  if(NOT EXISTS ${svg})
    message(FATAL_ERROR "${report} wrote no ${item}.svg")
  endif()
  list(APPEND svgs ${svg})
endforeach()
foreach(report calibrate diagnose calibrate_scan uncertainty_stage verify uncertainty testpiece)
  file(GLOB written ${WORK}/${report}/*.svg)
  foreach(svg IN LISTS written)
    if(NOT svg IN_LIST svgs)
      message(FATAL_ERROR "${svg}: a report page this test does not know; add it to 'pages'")
    endif()
  endforeach()
endforeach()

# (1) Each renders without a word on stderr to a PNG of the size the SVG declares (pt at 96 dpi: 4/3 px per pt).
foreach(svg IN LISTS svgs)
  string(REGEX REPLACE "\\.svg$" ".png" png ${svg})
  execute_process(COMMAND ${RSVG} -o ${png} ${svg} RESULT_VARIABLE code ERROR_VARIABLE err)
  if(NOT code EQUAL 0 OR NOT err STREQUAL "")
    message(FATAL_ERROR "rsvg-convert ${svg}: exit ${code}\n${err}")
  endif()
  file(SIZE ${png} bytes)
  file(READ ${png} signature LIMIT 8 HEX)
  if(bytes LESS 5000 OR NOT signature STREQUAL "89504e470d0a1a0a")
    message(FATAL_ERROR "rsvg-convert ${svg}: ${png} is not a picture (${bytes} bytes, signature ${signature})")
  endif()
endforeach()

# (2) No text on text, none past the canvas.
execute_process(COMMAND ${CHECK} ${svgs} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "report pictures with text on text or past the canvas:\n${out}${err}")
endif()
list(LENGTH svgs count)
message(STATUS "${count} report pictures render and their text boxes are clean")
