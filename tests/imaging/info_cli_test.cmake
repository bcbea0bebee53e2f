# fvm info as a user runs it. The X3P is made here from its parts (main.xml with an inline DataList, its MD5 in
# md5checksum.hex, zipped by CMake), so the reader is checked against a file fvm did not write. Expects FVM, WORK
# and SUPPORT (tests/fvm/cli_support.cmake).
file(REMOVE_RECURSE ${WORK})
include(${SUPPORT})

# 1. A 3 x 2 X3P surface: 2 um x 3 um pixels, heights in metres, one invalid (empty) point.
set(xml [=[<?xml version="1.0" encoding="UTF-8"?>
<p:ISO5436_2 xmlns:p="http://www.opengps.eu/2008/ISO5436_2">
  <Record1><Revision>ISO5436 - 2000</Revision><FeatureType>SUR</FeatureType>
    <Axes>
      <CX><AxisType>I</AxisType><DataType>D</DataType><Increment>2e-06</Increment><Offset>0</Offset></CX>
      <CY><AxisType>I</AxisType><DataType>D</DataType><Increment>3e-06</Increment><Offset>0</Offset></CY>
      <CZ><AxisType>A</AxisType><DataType>D</DataType><Increment>1</Increment><Offset>0</Offset></CZ>
    </Axes>
  </Record1>
  <Record3>
    <MatrixDimension><SizeX>3</SizeX><SizeY>2</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    <DataList>
      <Datum>1e-06</Datum><Datum/><Datum>-2.5e-06</Datum><Datum>0</Datum><Datum>4e-05</Datum><Datum>1e-05</Datum>
    </DataList>
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
]=])
# An X3P of this main.xml, with its checksum file, zipped by CMake into ${WORK}/<name>.x3p.
function(zip_x3p name main_xml)
  file(MAKE_DIRECTORY ${WORK}/${name})
  file(WRITE ${WORK}/${name}/main.xml "${main_xml}")
  string(MD5 digest "${main_xml}")
  file(WRITE ${WORK}/${name}/md5checksum.hex "${digest} *main.xml\n")
  execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${WORK}/${name}.x3p --format=zip main.xml md5checksum.hex
                  WORKING_DIRECTORY ${WORK}/${name} RESULT_VARIABLE code)
  if(NOT code EQUAL 0)
    message(FATAL_ERROR "cannot zip the test X3P ${name}")
  endif()
endfunction()
zip_x3p(surface "${xml}")

run(0 info ${WORK}/surface.x3p --json)
string(JSON size_x GET "${OUT}" size_x)
string(JSON size_y GET "${OUT}" size_y)
string(JSON dx GET "${OUT}" dx_mm)
string(JSON dy GET "${OUT}" dy_mm)
string(JSON valid GET "${OUT}" valid_points)
string(JSON z_min GET "${OUT}" z_min_mm)
string(JSON z_max GET "${OUT}" z_max_mm)
string(JSON format GET "${OUT}" format)
if(NOT size_x EQUAL 3 OR NOT size_y EQUAL 2 OR NOT valid EQUAL 5 OR NOT format STREQUAL "x3p")
  message(FATAL_ERROR "info --json on the X3P: ${OUT}")
endif()
if(dx LESS 0.0019999 OR dx GREATER 0.0020001 OR dy LESS 0.0029999 OR dy GREATER 0.0030001)
  message(FATAL_ERROR "info --json: pixel ${dx} x ${dy} mm, expected 0.002 x 0.003")
endif()
# CMake prints the numbers with 17 digits: compare within a part in a million.
if(z_min LESS -0.0025000025 OR z_min GREATER -0.0024999975 OR z_max LESS 0.03999996 OR z_max GREATER 0.04000004)
  message(FATAL_ERROR "info --json: z range ${z_min} .. ${z_max} mm, expected -0.0025 .. 0.04")
endif()
run(0 info ${WORK}/surface.x3p)
if(NOT OUT MATCHES "valid points  5 of 6")
  message(FATAL_ERROR "info text output:\n${OUT}")
endif()

# Float64 heights keep their digits (issue 17: -808.368571682830 mm came back as -808.3686): the JSON prints the
# shortest text of the double the file holds.
string(REPLACE "<Datum>1e-06</Datum>" "<Datum>-0.808368571682830</Datum>" precise "${xml}")
zip_x3p(precise "${precise}")
run(0 info ${WORK}/precise.x3p --json)
if(NOT OUT MATCHES "\"z_min_mm\": -808\\.36857168283[0-9]*[,\n]")
  message(FATAL_ERROR "info --json on float64 heights: ${OUT}")
endif()

# An all-invalid surface is a valid file: no valid points, and no height range (null).
string(REGEX REPLACE "<Datum>[^<]*</Datum>" "<Datum/>" nothing "${xml}")
zip_x3p(nan "${nothing}")
run(0 info ${WORK}/nan.x3p --json)
string(JSON valid GET "${OUT}" valid_points)
string(JSON z_type TYPE "${OUT}" z_min_mm)
if(NOT valid EQUAL 0 OR NOT z_type STREQUAL "NULL")
  message(FATAL_ERROR "info --json on an all-invalid X3P: ${OUT}")
endif()

# 2. Three points of XYZ text: an unorganised cloud, no grid (null pixel size).
file(WRITE ${WORK}/three.xyz "# x y z in mm\n1 2 3\n4 5 6\n7 8 -9\n")
run(0 info ${WORK}/three.xyz --json)
string(JSON size_x GET "${OUT}" size_x)
string(JSON dx_type TYPE "${OUT}" dx_mm)
string(JSON z_min GET "${OUT}" z_min_mm)
string(JSON kind GET "${OUT}" kind)
if(NOT size_x EQUAL 3 OR NOT dx_type STREQUAL "NULL" OR NOT z_min EQUAL -9 OR NOT kind STREQUAL "point_cloud")
  message(FATAL_ERROR "info --json on three points: ${OUT}")
endif()

# 3. Bad input: the file is named, the exit code is non-zero.
file(READ ${WORK}/surface/main.xml edited)
string(REPLACE "<Datum>0</Datum>" "<Datum>7</Datum>" edited "${edited}")
file(WRITE ${WORK}/surface/main.xml "${edited}")
execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${WORK}/edited.x3p --format=zip main.xml md5checksum.hex
                WORKING_DIRECTORY ${WORK}/surface)
fails_naming("edited.x3p.*md5checksum.hex" info ${WORK}/edited.x3p --json)
file(WRITE ${WORK}/empty.x3p "")
fails_naming("empty.x3p" info ${WORK}/empty.x3p)
fails_naming("missing.al3d: no such file" info ${WORK}/missing.al3d)

# An ISO 25178-71 SDF (ASCII) written here: 2 x 2 heights 1, 2, 3, 4 um, so Sq = sqrt(1.25) = 1.1180340 um.
file(WRITE ${WORK}/s.sdf "aISO-1.0\nManufacID = CMAKE\nNumPoints = 2\nNumProfiles = 2\nXscale = 1E-6\nYscale = 1E-6\nZscale = 1E-6\n*\n1 2\n3 4\n*\n")
run(0 info ${WORK}/s.sdf --json)
string(JSON format GET "${OUT}" format)
string(JSON sq GET "${OUT}" sq_um)
if(NOT format STREQUAL "sdf" OR sq LESS 1.1180339 OR sq GREATER 1.1180341)
  message(FATAL_ERROR "info --json on the SDF: format ${format}, sq_um ${sq}, expected sdf and 1.1180340")
endif()
run(0 info ${WORK}/s.sdf)
if(NOT OUT MATCHES "Sq            1.11803 um")
  message(FATAL_ERROR "info on the SDF does not report Sq 1.11803 um:\n${OUT}")
endif()

# 4. The X3P as a desktop archiver leaves it (issue 46): zipped around its folder with macOS's __MACOSX/ and
# .DS_Store beside it, the root without its namespace and an empty <Offset/>. It reads, and says so in "notes".
string(REPLACE "<p:ISO5436_2 xmlns:p=\"http://www.opengps.eu/2008/ISO5436_2\">" "<ISO5436_2>" found "${xml}")
string(REPLACE "</p:ISO5436_2>" "</ISO5436_2>" found "${found}")
string(REPLACE "<Increment>2e-06</Increment><Offset>0</Offset>" "<Increment>2e-06</Increment><Offset/>" found "${found}")
file(MAKE_DIRECTORY ${WORK}/desktop/scan ${WORK}/desktop/__MACOSX/scan)
file(WRITE ${WORK}/desktop/scan/main.xml "${found}")
string(MD5 digest "${found}")
file(WRITE ${WORK}/desktop/scan/md5checksum.hex "${digest} *main.xml\n")
file(WRITE ${WORK}/desktop/scan/.DS_Store "Bud1")
file(WRITE ${WORK}/desktop/__MACOSX/scan/._main.xml "Mac OS X resource fork")
execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${WORK}/desktop.x3p --format=zip scan __MACOSX
                WORKING_DIRECTORY ${WORK}/desktop RESULT_VARIABLE code)
run(0 info ${WORK}/desktop.x3p --json)
string(JSON valid GET "${OUT}" valid_points)
string(JSON notes LENGTH "${OUT}" notes)
string(JSON first GET "${OUT}" notes 0)
if(NOT valid EQUAL 5 OR notes LESS 4 OR NOT first MATCHES "inside the folder 'scan/'")
  message(FATAL_ERROR "info --json on the desktop-zipped X3P: ${OUT}")
endif()
run(0 info ${WORK}/desktop.x3p)
if(NOT OUT MATCHES "note          the archive holds 2 files a desktop archiver adds")
  message(FATAL_ERROR "info on the desktop-zipped X3P does not note the clutter:\n${OUT}")
endif()
run(0 info ${WORK}/s.sdf --json)
string(JSON notes LENGTH "${OUT}" notes)
if(NOT notes EQUAL 0)
  message(FATAL_ERROR "info --json on a plain SDF has notes: ${OUT}")
endif()
