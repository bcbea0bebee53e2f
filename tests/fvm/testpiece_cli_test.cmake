# fvm testpiece as a user runs it: the published piece's design (NOMINAL.csv, CMM program, G-code), a piece cut by
# [Lorente 2021] Table 4's machine and measured with 1 um CMM noise, its verification's JSON contract and report, the
# 167-point pyramid with Legendre, and bad input (a piece whose features collide) that exits 1 and writes nothing.
# Variables: FVM (the executable), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

run(0 testpiece design -o ${WORK}/nominal.csv --cmm ${WORK}/cmm --gcode ${WORK}/piece.nc --describe ${WORK}/piece.json --json)
string(JSON points GET "${OUT}" points)
if(NOT points EQUAL 480)
  message(FATAL_ERROR "the published piece has ${points} points, [Lorente 2021] measures 480")
endif()
expect_files("fvm testpiece design" ${WORK} nominal.csv piece.nc piece.json cmm/program.txt)
file(STRINGS ${WORK}/nominal.csv header LIMIT_COUNT 1)
if(NOT header STREQUAL "id,x,y,z,series")
  message(FATAL_ERROR "NOMINAL.csv header: ${header}")
endif()
# The description written back is the same piece.
run(0 testpiece design ${WORK}/piece.json -o ${WORK}/again.csv)
file(READ ${WORK}/nominal.csv a)
file(READ ${WORK}/again.csv b)
if(NOT a STREQUAL b)
  message(FATAL_ERROR "the piece read back from --describe gives other points")
endif()

run(0 simulate testpiece -o ${WORK}/tp --validation 30,30,30)
# truth.json names the default errors by their source's key (docs/bibliography.md).
file(READ ${WORK}/tp/truth.json truth)
string(JSON errors GET "${truth}" errors)
if(NOT errors STREQUAL "[Lorente 2021] Table 4")
  message(FATAL_ERROR "truth.json errors: '${errors}', expected '[Lorente 2021] Table 4'")
endif()
run(0 testpiece verify ${WORK}/tp/measured.csv --basis chebyshev --order 2 --nominal ${WORK}/tp/nominal.csv
    --validate ${WORK}/tp/validation.csv --json --report ${WORK}/report)
expect_json_keys("fvm testpiece verify" "${OUT}" points initial/mean_um initial/max_um initial/min_um final/mean_um
                 validation/points validation/initial/mean_um validation/final/mean_um iterations/0/max_um
                 iterations/0/mean_um iterations/0/min_um geometric/0/error geometric/0/recoverable
                 geometric/0/value_um_or_urad geometric/0/u fixed/0/name fixed/0/reason pose datum_absorbs)
# Table 4's functions are quadratics: order 2 leaves the CMM noise (1 um per coordinate: 1.6 um mean in 3D) and
# predicts the noise-free grid to a fraction of a micrometre.
string(JSON final GET "${OUT}" final mean_um)
string(JSON grid GET "${OUT}" validation final mean_um)
expect_near("final mean (um)" "${final}" 1.55 0.2)
expect_near("validation grid mean (um)" "${grid}" 0.3 0.3)
string(JSON ecz GET "${OUT}" geometric 17 error)
string(JSON ecz_ok GET "${OUT}" geometric 17 recoverable)
if(NOT ecz STREQUAL "ECZ" OR ecz_ok)
  message(FATAL_ERROR "ECZ should be named unrecoverable by the series (a tool on the spindle axis): ${ecz} ${ecz_ok}")
endif()
expect_files("fvm testpiece verify --report" ${WORK}/report index.html)
file(READ ${WORK}/report/index.html page)
foreach(part "Iterations" "Histogram of the volumetric errors" "Geometric verification")
  string(FIND "${page}" "${part}" at)
  if(at LESS 0)
    message(FATAL_ERROR "report index.html does not mention '${part}'")
  endif()
endforeach()

# The proposed series: cut again with an off-axis boring bar and a longer tool, ECZ becomes recoverable.
run(0 simulate testpiece -o ${WORK}/proposed --points series --proposed-series)
run(0 testpiece verify ${WORK}/proposed/measured.csv --order 2 --nominal ${WORK}/proposed/nominal.csv
    --machine 300x270x180 --tool 0,0,100 --tool 30,0,100 --tool -30,0,100 --tool 0,0,150 --json)
string(JSON ecz GET "${OUT}" geometric 17 error)
string(JSON ecz_ok GET "${OUT}" geometric 17 recoverable)
string(JSON ecz_value GET "${OUT}" geometric 17 value_um_or_urad)
if(NOT ecz STREQUAL "ECZ" OR NOT ecz_ok)
  message(FATAL_ERROR "the proposed series should recover ECZ: ${ecz} ${ecz_ok}")
endif()
# Table 4: ECZ(180) = 6.1e-6 * 180 + 6.2e-10 * 180^2 = 1118 urad from z 0 (--machine: the series start at z 10).
expect_near("ECZ at z 180 (urad)" "${ecz_value}" 1118 40 0)

run(0 simulate testpiece -o ${WORK}/pyramid --points pyramid)
run(0 testpiece verify ${WORK}/pyramid/measured.csv --basis legendre --order 2 --json)
string(JSON points GET "${OUT}" points)
if(NOT points EQUAL 167)
  message(FATAL_ERROR "the pyramid has ${points} points, [Lorente 2021] measures 167")
endif()

file(WRITE ${WORK}/bad.json [=[{"envelope_mm": [100, 100, 50], "features": [
  {"name": "S1", "kind": "slot", "min_mm": [10, 10, 40], "max_mm": [90, 30, 50]},
  {"name": "H7", "kind": "hole", "min_mm": [20, 20, 45], "max_mm": [25, 25, 50], "points": [{"x": 22, "y": 22, "z": 50}]}]}]=])
fails_naming("bad.json: the piece cannot be made .*slot S1 and hole H7 collide" testpiece design ${WORK}/bad.json -o ${WORK}/bad.csv)
if(EXISTS ${WORK}/bad.csv)
  message(FATAL_ERROR "a refused piece left bad.csv behind")
endif()
file(WRITE ${WORK}/meas-bad.csv "id,x,y,z,xm,ym,zm\nA,0,0,0,1,2,3\nB,10,0,0,x,2,3\n")
fails_naming("meas-bad.csv:3: point B: column 'xm'" testpiece verify ${WORK}/meas-bad.csv)
