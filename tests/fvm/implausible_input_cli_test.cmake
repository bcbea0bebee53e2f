# Data that no machine or network can have: each refused with exit 1, a reason the user can act on, and nothing
# written (issue 35). Mirrored tracker and CMM readings, identical readings, ranges that do not meet, a
# self-calibration that collapses, the same scan twice, a directory or a header-less CSV as readings; and a clean
# run prints nothing on stderr (no glog lines).
# Variables: FVM (the executable), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# Rewrites a readings CSV: the column `column` of every data row through `mode` (negate: -v; constant: 0).
function(rewrite_column in out column mode)
  file(STRINGS ${in} lines)
  set(text "")
  set(header "")
  foreach(line IN LISTS lines)
    if(line MATCHES "^#" OR header STREQUAL "")
      if(NOT line MATCHES "^#")
        string(REPLACE "," ";" header "${line}")
        list(FIND header ${column} index)
      endif()
      string(APPEND text "${line}\n")
      continue()
    endif()
    string(REPLACE "," ";" fields "${line}")
    list(GET fields ${index} value)
    if(mode STREQUAL "negate")
      if(value MATCHES "^-")
        string(SUBSTRING "${value}" 1 -1 value)
      else()
        set(value "-${value}")
      endif()
    else()
      set(value 0)
    endif()
    list(REMOVE_AT fields ${index})
    list(INSERT fields ${index} "${value}")
    string(REPLACE ";" "," line "${fields}")
    string(APPEND text "${line}\n")
  endforeach()
  file(WRITE ${out} "${text}")
endfunction()

# Refused with exit 1, stderr matching every pattern given after the arguments (ARGS ... MATCHES ...), and no
# output file `written`.
function(refused written)
  cmake_parse_arguments(R "" "" "ARGS;MATCHES" ${ARGN})
  execute_process(COMMAND ${FVM} ${R_ARGS} RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL 1)
    message(FATAL_ERROR "fvm ${R_ARGS}: exit ${code}, expected 1\n${out}\n${err}")
  endif()
  foreach(pattern IN LISTS R_MATCHES)
    if(NOT err MATCHES "${pattern}")
      message(FATAL_ERROR "fvm ${R_ARGS}: stderr does not say '${pattern}':\n${err}")
    endif()
  endforeach()
  if(NOT written STREQUAL "" AND EXISTS ${written})
    message(FATAL_ERROR "fvm ${R_ARGS}: refused but wrote ${written}")
  endif()
endfunction()

# --- A laser tracker's readings with z mirrored: the fit would explain it by zTz = -2 x travel (-2400 mm).
run(0 simulate tracker --seed 1 -o ${WORK}/plan)
run(0 simulate tracker --seed 1 --stations ${SAMPLES}/stations/spread-4.json -o ${WORK}/net)
# A clean run says nothing on stderr: no glog or Ceres lines.
run(0 verify ${WORK}/plan/readings.csv --chain XFYZ --order 3 --tool 0,0,100 --json)
if(NOT ERR STREQUAL "")
  message(FATAL_ERROR "a clean fvm verify wrote to stderr:\n${ERR}")
endif()
rewrite_column(${WORK}/plan/readings.csv ${WORK}/mirrored.csv zt negate)
refused(${WORK}/machine.json ARGS verify ${WORK}/mirrored.csv --chain XFYZ --order 3 --tool 0,0,100 -o ${WORK}/machine.json
        MATCHES "mirrored.csv: zTz1 = -1200 mm" "zTz reaches -2400 mm" "bound 2.5 mm: 1 mm per metre" "mirrored"
                "--max-error-mm")
# The bound is the user's: raised beyond 2.4 m, the same fit goes through (the fit itself is not the problem).
run(0 verify ${WORK}/mirrored.csv --chain XFYZ --order 3 --tool 0,0,100 --max-error-mm 3000 --json)
# fvm uncertainty identifies the same way, and refuses before any Monte Carlo run.
refused("" ARGS uncertainty ${WORK}/mirrored.csv --chain XFYZ --order 3 --tool 0,0,100 --runs 10
        MATCHES "zTz1 = -1200 mm" "mirrored")
# Every reading the same point: rank-deficient, the parameters named.
rewrite_column(${WORK}/plan/readings.csv ${WORK}/same_x.csv xt constant)
rewrite_column(${WORK}/same_x.csv ${WORK}/same_xy.csv yt constant)
rewrite_column(${WORK}/same_xy.csv ${WORK}/same.csv zt constant)
refused(${WORK}/same.json ARGS verify ${WORK}/same.csv --tracker none --tool 0,0,100 -o ${WORK}/same.json
        MATCHES "every reading is \\(nearly\\) the same point" "rank-deficient" "pose_rx" "xTx1")
refused("" ARGS verify ${WORK}/same_x.csv --tool 0,0,100 MATCHES "the readings lie in a plane" "rank-deficient")

# --- A test piece whose CMM z is mirrored; and one whose every point reads the same.
run(0 simulate testpiece -o ${WORK}/tp)
rewrite_column(${WORK}/tp/measured.csv ${WORK}/tp_mirrored.csv zm negate)
refused("" ARGS testpiece verify ${WORK}/tp_mirrored.csv --json MATCHES "zTz1 = " "mirrored" "--max-error-mm")
rewrite_column(${WORK}/tp/measured.csv ${WORK}/tp_x.csv xm constant)
rewrite_column(${WORK}/tp_x.csv ${WORK}/tp_xy.csv ym constant)
rewrite_column(${WORK}/tp_xy.csv ${WORK}/tp_same.csv zm constant)
refused("" ARGS testpiece verify ${WORK}/tp_same.csv MATCHES "the same point" "rank-deficient" "pose_rx")

# --- Multilateration: a simulated network's residuals are about half a sigma (the noise model's own scale); four ranges of 1000 mm to stations kilometres apart do not meet.
file(WRITE ${WORK}/far.json "{\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": 0, \"z\": 0},
  {\"name\": \"B\", \"x\": 5000, \"y\": 0, \"z\": 0}, {\"name\": \"C\", \"x\": 0, \"y\": 5000, \"z\": 0},
  {\"name\": \"D\", \"x\": 0, \"y\": 0, \"z\": 5000}]}\n")
file(WRITE ${WORK}/far.csv "id,station,range\nP1,A,1000\nP1,B,1000\nP1,C,1000\nP1,D,1000\n")
run(0 multilaterate ${WORK}/net/readings.csv --stations ${WORK}/net/stations.json --self-calibrate --json)
string(JSON sigmas GET "${OUT}" range_rms_sigmas)
expect_near("range rms of a consistent network (sigmas)" "${sigmas}" 0.5 0.3)
refused(${WORK}/far_points.csv ARGS multilaterate ${WORK}/far.csv --stations ${WORK}/far.json -o ${WORK}/far_points.csv
        MATCHES "far.csv: the ranges do not meet" "sigmas of the tracker's range noise" "point P1, station")
# A self-calibration of ranges of 1e-6 mm: the stations collapse onto one spot.
set(tiny "id,station,range\n")
foreach(p 1 2 3 4 5 6 7 8)
  foreach(s A B C D)
    string(APPEND tiny "P${p},${s},1e-6\n")
  endforeach()
endforeach()
file(WRITE ${WORK}/tiny.csv "${tiny}")
refused(${WORK}/tiny_points.csv ARGS multilaterate ${WORK}/tiny.csv --stations ${WORK}/far.json --self-calibrate
        -o ${WORK}/tiny_points.csv MATCHES "collapsed onto one spot" "units")

# --- Readings that are not a readings CSV.
refused("" ARGS verify ${WORK}/plan --tool 0,0,100 MATCHES "is a directory, not a file; name the CSV table" "id,x,y,z")
file(STRINGS ${WORK}/plan/readings.csv lines REGEX "^P")
string(REPLACE ";" "\n" rows "${lines}")
file(WRITE ${WORK}/headerless.csv "${rows}\n")
refused("" ARGS verify ${WORK}/headerless.csv --tool 0,0,100 MATCHES "the header line is missing" "id,x,y,z")
