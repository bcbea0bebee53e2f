# fvm stitch with Fiji's tile configuration (issue 43): --layout TileConfiguration.txt (told by its 'dim =' line,
# whatever its name) stitches as its CSV layout does, -o NAME.txt writes the same positions in Fiji's registered form,
# and a bad configuration is refused naming its file and line with nothing written.
include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

run(0 tiles synthesize -o ${WORK}/set --rows 2 --cols 3 --size 256 --bits 8 --seed 4)
run(0 stitch --layout ${WORK}/set/layout.csv --overlap 20 -o ${WORK}/set/positions.csv)
# The configuration Fiji's Grid stitching writes for it: serpentine, at the nominal grid (256 px x 0.8 apart).
file(WRITE ${WORK}/set/TileConfiguration.txt "# Define the number of dimensions we are working on\ndim = 2\n\n"
  "# Define the image coordinates\ntile_r000_c000.tif; ; (0.0, 0.0)\ntile_r000_c001.tif; ; (204.8, 0.0)\n"
  "tile_r000_c002.tif; ; (409.6, 0.0)\ntile_r001_c002.tif; ; (409.6, 204.8)\ntile_r001_c001.tif; ; (204.8, 204.8)\n"
  "tile_r001_c000.tif; ; (0.0, 204.8)\n")
run(0 stitch --layout ${WORK}/set/TileConfiguration.txt --overlap 20 -o ${WORK}/set/fiji.csv --json)
string(JSON nominal GET "${OUT}" nominal)
if(NOT nominal STREQUAL "stage")
  message(FATAL_ERROR "the configuration's positions were not the nominal ones: ${nominal}")
endif()
run(0 stitch --layout ${WORK}/set/TileConfiguration.txt --overlap 20 -o ${WORK}/set/TileConfiguration.registered.txt)
if(NOT OUT MATCHES "positions written to .*TileConfiguration.registered.txt")
  message(FATAL_ERROR "fvm stitch -o NAME.txt said:\n${OUT}")
endif()
# The registered form: Fiji's comment lines, dim = 2, then each tile with the positions CSV's x and y to the digit.
file(STRINGS ${WORK}/set/positions.csv csv)
file(STRINGS ${WORK}/set/fiji.csv fiji_csv)
file(STRINGS ${WORK}/set/TileConfiguration.registered.txt registered)
list(GET registered 1 dim)
if(NOT dim STREQUAL "dim = 2")
  message(FATAL_ERROR "registered configuration's second line: '${dim}'")
endif()
list(LENGTH registered n)
if(NOT n EQUAL 9)  # file(STRINGS) drops the blank line: 3 comment and dim lines, 6 tiles
  message(FATAL_ERROR "registered configuration: ${n} lines\n${registered}")
endif()
foreach(i RANGE 1 6)
  list(GET fiji_csv ${i} row)
  string(REPLACE "," ";" row "${row}")
  list(GET row 0 file)
  list(GET row 1 x)
  list(GET row 2 y)
  math(EXPR k "${i} + 2")
  list(GET registered ${k} line)
  if(NOT line STREQUAL "${file}; ; (${x}, ${y})")
    message(FATAL_ERROR "registered line '${line}', the positions CSV says ${file} at ${x}, ${y}")
  endif()
  # The same tile in the CSV layout's run, wherever the layout lists it.
  foreach(other IN LISTS csv)
    if(other MATCHES "^${file},([^,]+),([^,]+),")
      expect_near("${file} x (configuration vs CSV layout)" ${x} ${CMAKE_MATCH_1} 0.001)
      expect_near("${file} y (configuration vs CSV layout)" ${y} ${CMAKE_MATCH_2} 0.001)
    endif()
  endforeach()
endforeach()
# Fiji's registered form reads back as a layout, its name ending in .txt or not.
file(COPY_FILE ${WORK}/set/TileConfiguration.registered.txt ${WORK}/set/registered.layout)
run(0 stitch --layout ${WORK}/set/registered.layout --overlap 20 -o ${WORK}/set/again.csv)

# Bad configurations: exit 1, the message names the file and line, no output written.
function(refused what pattern)
  file(REMOVE ${WORK}/set/bad.csv)
  run(1 stitch ${ARGN} -o ${WORK}/set/bad.csv)
  if(NOT ERR MATCHES "${pattern}" OR EXISTS ${WORK}/set/bad.csv)
    message(FATAL_ERROR "${what} was not refused by name, or left an output:\n${ERR}")
  endif()
endfunction()
file(WRITE ${WORK}/set/bad.txt "dim = 2\ntile_r000_c000.tif; ; (0.0, 0.0)\ntile_r000_c001.tif, (204.8, 0.0)\n")
refused("a malformed line"
        "bad.txt:3: cannot read 'tile_r000_c001.tif, \\(204.8, 0.0\\)' as a tile; write 'name; ; \\(x, y\\)'"
        --layout ${WORK}/set/bad.txt --overlap 20)
file(WRITE ${WORK}/set/between.txt "dim = 2\ntile_r000_c000.tif; ; (0.0, 0.0)\ntile_r000_c001.tif; ; (102.4, 0.0)\n")
refused("a tile between two columns"
        "between.txt:3: tile tile_r000_c001.tif at x = 102.4 px is 102.4 px from the nearest column of the grid \\(pitch 204.8 px\\): it lies on no node"
        --layout ${WORK}/set/between.txt --overlap 20)
# A wrong --overlap (60 % of 256 px: a pitch of 102.4 px where the tiles step by 204.8) is named, not stitched.
refused("a wrong overlap"
        "TileConfiguration.txt: no two columns of the grid are neighbours: the nearest lie 2 pitches of 102.4 px apart along x; check --overlap"
        --layout ${WORK}/set/TileConfiguration.txt --overlap 60)
file(WRITE ${WORK}/set/stacks.txt "dim = 3\ntile_r000_c000.tif; ; (0.0, 0.0, 0.0)\ntile_r000_c001.tif; ; (204.8, 0.0, 3.0)\n")
refused("tiles in several planes"
        "stacks.txt:3: tile tile_r000_c001.tif is at z = 3 px, the first tile at z = 0: tiles in several planes"
        --layout ${WORK}/set/stacks.txt --overlap 20)
file(WRITE ${WORK}/set/absent.txt "dim = 2\ntile_r000_c000.tif; ; (0.0, 0.0)\nnone.tif; ; (204.8, 0.0)\n")
refused("a missing tile" "absent.txt:3: tile row 0 col 1: .*none.tif" --layout ${WORK}/set/absent.txt --overlap 20)
refused("a missing configuration" "nothing.txt" --layout ${WORK}/set/nothing.txt --overlap 20)
# A tile name Fiji cannot read back is refused before anything is written.
file(COPY_FILE ${WORK}/set/tile_r000_c000.tif "${WORK}/set/a;b.tif")
file(WRITE ${WORK}/set/semicolon.csv "file,row,col\na;b.tif,0,0\ntile_r000_c001.tif,0,1\n")
run(1 stitch --layout ${WORK}/set/semicolon.csv --overlap 20 -o ${WORK}/set/bad.txt.txt)
if(NOT ERR MATCHES "Fiji cannot read this name back" OR EXISTS ${WORK}/set/bad.txt.txt)
  message(FATAL_ERROR "a name with ';' was written as Fiji's:\n${ERR}")
endif()
file(REMOVE_RECURSE ${WORK})
