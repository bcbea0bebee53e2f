# fvm tiles and fvm stitch as a user runs them: the published 225 vs 49 tiles, a synthetic tile set stitched back
# to its truth, and bad input. Variables: FVM (the executable), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

# A plain decimal string as an integer in units of 10^-digits (CMake has integer arithmetic only).
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# The published example: 6 x 6 grid, 10x lens, 225 tiles stitched vs 49 stitching-free (13 % overlap over the
# calottes' bounding box; see tests/imaging/tile_plan_test.cc for why).
run(0 tiles plan --lens 10x --artefact grid6x6 --overlap 13 --json -o ${WORK}/stitched.csv
    --free-layout ${WORK}/free.csv)
string(JSON stitched GET "${OUT}" stitched tiles)
string(JSON free GET "${OUT}" stitching_free tiles)
if(NOT stitched EQUAL 225 OR NOT free EQUAL 49)
  message(FATAL_ERROR "grid6x6 at 10x: ${stitched} stitched / ${free} stitching-free tiles, expected 225 / 49")
endif()
file(STRINGS ${WORK}/stitched.csv lines)
list(LENGTH lines n)
list(GET lines 1 header)
list(GET lines 2 first)
if(NOT n EQUAL 227 OR NOT header STREQUAL "file,row,col,x,y" OR NOT first MATCHES "^tile_r000_c000.tif,0,0,0.56")
  message(FATAL_ERROR "stitched layout: ${n} lines, header '${header}', first tile '${first}'")
endif()
# Scan order: down the first column (+Y to -Y), then the next column.
list(GET lines 3 second)
list(GET lines 17 sixteenth)
if(NOT second MATCHES "^tile_r001_c000" OR NOT sixteenth MATCHES "^tile_r000_c001")
  message(FATAL_ERROR "scan order: second '${second}', sixteenth '${sixteenth}'")
endif()
file(STRINGS ${WORK}/free.csv lines)
list(LENGTH lines n)
if(NOT n EQUAL 51)
  message(FATAL_ERROR "stitching-free layout: ${n} lines, expected comment + header + 49 tiles")
endif()
run(0 tiles plan --lens 5x --region 0,0,10,10 --overlap 0.2)
if(NOT OUT MATCHES "stitched +25 " OR OUT MATCHES "stitching-free")
  message(FATAL_ERROR "5x over 10 mm at 20 %: expected 5 x 5 tiles and no stitching-free line:\n${OUT}")
endif()

# Synthetic tiles with known positions (8-bit, noise, vignetting): stitched back to within 0.15 px per axis (the
# set's RMS is 0.04 px; the bound leaves room for the 8-bit quantisation on other platforms' random streams).
run(0 tiles synthesize -o ${WORK}/set --rows 3 --cols 3 --size 256 --bits 8 --seed 4)
run(0 stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/set/positions.csv --pixel-mm 0.001)
# stderr is a pipe here, not a terminal: no progress line (no carriage returns in logs).
if(ERR MATCHES "registering pairs|\r")
  message(FATAL_ERROR "fvm stitch drew progress into a pipe:\n${ERR}")
endif()
file(STRINGS ${WORK}/set/positions.csv positions)
file(STRINGS ${WORK}/set/truth.csv truth)
list(GET positions 0 header)
if(NOT header STREQUAL "file,x,y,x_mm,y_mm,registered,u_x,u_y")
  message(FATAL_ERROR "positions header '${header}'")
endif()
foreach(i RANGE 1 9)
  list(GET positions ${i} p)
  list(GET truth ${i} t)
  string(REPLACE "," ";" p "${p}")
  string(REPLACE "," ";" t "${t}")
  list(GET p 0 file)
  list(GET p 1 x)
  list(GET p 2 y)
  list(GET p 5 registered)
  list(GET t 1 tx)
  list(GET t 2 ty)
  expect_near("${file} x" ${x} ${tx} 0.15)
  expect_near("${file} y" ${y} ${ty} 0.15)
  if(NOT registered EQUAL 1)
    message(FATAL_ERROR "${file} was not registered")
  endif()
endforeach()

# The fused mosaic: 8-bit like its tiles, as wide as three tiles at 80 % steps (665.6 px) give or take the stage
# error (1.5 px per tile); an X3P height map needs float tiles and the pixel size, and sits in the stage frame.
run(0 stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/set/positions.csv --mosaic ${WORK}/set/mosaic.png)
run(0 info ${WORK}/set/mosaic.png --pixel-size 0.001 --z-scale 1 --json)
string(JSON size_x GET "${OUT}" size_x)
string(JSON size_y GET "${OUT}" size_y)
if(size_x LESS 656 OR size_x GREATER 676 OR size_y LESS 656 OR size_y GREATER 676)
  message(FATAL_ERROR "mosaic of 3 x 3 tiles is ${size_x} x ${size_y} px, expected about 666 x 666")
endif()
fails_naming("--mosaic .*m.x3p: an X3P height map needs the pixel size"
             stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/bad.csv --mosaic ${WORK}/m.x3p)
fails_naming("the tiles hold 8-bit counts, not heights"
             stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/bad.csv --mosaic ${WORK}/m.x3p --pixel-mm 0.001)
if(EXISTS ${WORK}/bad.csv OR EXISTS ${WORK}/m.x3p)
  message(FATAL_ERROR "a refused mosaic left output behind")
endif()
run(0 tiles synthesize -o ${WORK}/heights --rows 2 --cols 2 --size 128 --bits 32 --seed 3)
run(0 stitch --layout ${WORK}/heights/layout.csv --overlap 20 -o ${WORK}/heights/p.csv --pixel-mm 0.002
    --mosaic ${WORK}/heights/m.x3p)
run(0 info ${WORK}/heights/m.x3p --json)
string(JSON dx GET "${OUT}" dx_mm)
string(JSON x0 GET "${OUT}" x0_mm)
# The first tile's centre is the origin: its top-left pixel sits 63.5 px to the left.
expect_near("height map dx" ${dx} 0.002 0.000001 6)
expect_near("height map x0" ${x0} -0.127 0.000001 6)

# What an instrument exports, end to end: height-map tiles of the 6 x 6 grid (float, NaN on the steep flanks,
# roughness as the only texture), stitched into one X3P, the calottes found and numbered in it, and their
# distances compared with the true calottes: within 0.5 um over 28 mm (measured 0.24 um; the fits on 0.5 um of
# roughness and 0.01 px of registration at 10 um pixels).
run(0 tiles synthesize --artefact grid6x6 -o ${WORK}/grid --seed 2)
run(0 stitch --layout ${WORK}/grid/layout.csv --overlap 20 --pixel-mm 0.01 -o ${WORK}/grid/p.csv
    --mosaic ${WORK}/grid/m.x3p --json)
string(JSON accepted GET "${OUT}" pairs_accepted)
if(NOT accepted EQUAL 220)
  message(FATAL_ERROR "grid6x6 height tiles: ${accepted} of 220 pairs accepted")
endif()
run(0 fit ${WORK}/grid/m.x3p --artefact grid6x6 -o ${WORK}/grid/c.csv)
run(0 diff ${WORK}/grid/calottes.csv ${WORK}/grid/c.csv --json)
string(JSON n LENGTH "${OUT}" pairs)
if(NOT n EQUAL 35)
  message(FATAL_ERROR "the stitched grid gave ${n} calotte distances, expected 35")
endif()
math(EXPR last "${n} - 1")
foreach(k RANGE ${last})
  string(JSON d GET "${OUT}" pairs ${k} diff_um)
  expect_near("stitched distance ${k}" ${d} 0 0.5)
endforeach()

# Bad input: exit 1 (2 for an option value), the message names the culprit, no output written.
run(2 stitch --layout ${WORK}/set/layout.csv --overlap 0 -o ${WORK}/bad.csv)
if(NOT ERR MATCHES "--overlap '0': tiles must overlap" OR EXISTS ${WORK}/bad.csv)
  message(FATAL_ERROR "overlap 0 was not refused:\n${ERR}")
endif()
file(WRITE ${WORK}/missing.csv "file,row,col\nset/tile_r000_c000.tif,0,0\nset/absent.tif,0,1\n")
run(1 stitch --layout ${WORK}/missing.csv --overlap 20 -o ${WORK}/bad.csv)
if(NOT ERR MATCHES "missing.csv:3: tile row 0 col 1: .*absent.tif" OR EXISTS ${WORK}/bad.csv)
  message(FATAL_ERROR "a missing tile was not named with layout line and tile:\n${ERR}")
endif()
run(0 tiles synthesize -o ${WORK}/small --rows 1 --cols 1 --size 128 --seed 2)
file(WRITE ${WORK}/sizes.csv "file,row,col\nset/tile_r000_c000.tif,0,0\nsmall/tile_r000_c000.tif,0,1\n")
run(1 stitch --layout ${WORK}/sizes.csv --overlap 20 -o ${WORK}/bad.csv)
if(NOT ERR MATCHES "sizes.csv:3: tile row 0 col 1: small/tile_r000_c000.tif is 128 x 128 px but .* is 256 x 256")
  message(FATAL_ERROR "inconsistent tile sizes were not named:\n${ERR}")
endif()
file(WRITE ${WORK}/apart.csv "file,row,col\nset/tile_r000_c000.tif,0,0\nset/tile_r001_c001.tif,1,1\n")
run(1 stitch --layout ${WORK}/apart.csv --overlap 20 -o ${WORK}/bad.csv)
if(NOT ERR MATCHES "apart.csv:2: no two tiles are neighbours \\(tile set/tile_r000_c000.tif at row 0 col 0" OR EXISTS ${WORK}/bad.csv)
  message(FATAL_ERROR "a layout without two neighbours was not refused:\n${ERR}")
endif()
# A layout with a hole (a region that is not a rectangle) is stitched with the neighbours each tile has.
file(WRITE ${WORK}/holes.csv "file,row,col\nset/tile_r000_c000.tif,0,0\nset/tile_r000_c001.tif,0,1\nset/tile_r001_c001.tif,1,1\n")
run(0 stitch --layout ${WORK}/holes.csv --overlap 20 -o ${WORK}/holes_positions.csv)
file(STRINGS ${WORK}/holes_positions.csv HOLE_ROWS)
list(LENGTH HOLE_ROWS HOLE_COUNT)
if(NOT HOLE_COUNT EQUAL 4)
  message(FATAL_ERROR "a layout with a hole was not stitched (header and 3 tiles expected):\n${OUT}${ERR}")
endif()
run(1 tiles plan --lens 15x --region 0,0,1,1)
if(NOT ERR MATCHES "lens '15x' is unknown; use one of 2.5x")
  message(FATAL_ERROR "an unknown lens was not named:\n${ERR}")
endif()
run(1 tiles plan --artefact grid6x6 --region 0,0,5,5)
if(NOT ERR MATCHES "feature 1 at .* is not wholly inside the tile grid")
  message(FATAL_ERROR "a feature outside the region was not named:\n${ERR}")
endif()
# Issue 13: a sparse set (thin 6 % overlaps, blobs, a drifting stage). Its thin overlaps go to the widened search,
# whose candidates --json lists per pair; the stage model comes from the pairs that pass.
run(0 tiles synthesize --texture sparse -o ${WORK}/sparse --seed 2)
run(0 stitch --layout ${WORK}/sparse/layout.csv --overlap 6 -o ${WORK}/sparse/p.csv --json)
expect_json_keys("fvm stitch (sparse)" "${OUT}" stage_model/east_step_px stage_model/east_drift_px
                 stage_model/south_step_px stage_model/repeatability_px pairs/0/searched pairs/0/candidates/0/dx_px
                 pairs/0/candidates/0/ncc pairs/0/search_px)
string(JSON east_pairs GET "${OUT}" stage_model east_pairs)
string(JSON searched GET "${OUT}" pairs 0 searched)
if(east_pairs LESS 3 OR NOT searched)
  message(FATAL_ERROR "sparse set: ${east_pairs} east pairs in the stage model, first pair searched: ${searched}")
endif()
file(REMOVE_RECURSE ${WORK})
