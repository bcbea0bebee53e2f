# Commands that never meet an image or a PCD/PLY file must not load OpenImageIO, PCL or VTK (half a second and
# 130 MB at start-up, issue 15), nor OpenCV and what its video module drags in (dnn, calib3d, protobuf, X11, GL:
# 25 ms before main, issue 47), nor libzip with the libcrypto and libbz2 it pulls, pugixml and OpenSSL's MD5 (the
# X3P, PLUx and LEXT code: half the dynamic loader's relocations of a calibrate, issue 47), nor PLplot without a
# report: the dynamic loader's own log (LD_DEBUG=libs) lists every library a process loads. The positive controls
# show the log does name them when a TIFF or an X3P is read, tiles are registered and a report is written, and that
# without the plugins a TIFF, an X3P or a focus stack fails with a clear message while an XYZ cloud still reads.
# Variables: FVM, SAMPLES, WORK.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK}/ld ${WORK}/x3p ${WORK}/no-plugins)
include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

# The libraries, and the plugins that load them on demand.
set(heavy "libOpenImageIO|libpcl_|libvtk|libopencv_|libprotobuf|libX11|libGL|libplplot")
string(APPEND heavy "|libzip|libcrypto|libbz2|libpugixml")
string(APPEND heavy "|libfvm_image_oiio|libfvm_cloud_pcl|libfvm_imaging_opencv|libfvm_zip_xml_formats|libfvm_report")

# Runs fvm with the loader's log in ${WORK}/ld/<tag>.<pid>; sets LOADED to the log's text.
function(run_logged tag expected_code)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env LD_DEBUG=libs LD_DEBUG_OUTPUT=${WORK}/ld/${tag} ${FVM} ${ARGN}
                  RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT code EQUAL expected_code)
    message(FATAL_ERROR "fvm ${ARGN}: exit ${code}, expected ${expected_code}\n${out}\n${err}")
  endif()
  file(GLOB logs ${WORK}/ld/${tag}.*)
  if(NOT logs)
    message(FATAL_ERROR "fvm ${ARGN}: the dynamic loader wrote no log to ${WORK}/ld/${tag}.*")
  endif()
  set(loaded "")
  foreach(log ${logs})
    file(READ ${log} text)
    string(APPEND loaded "${text}")
  endforeach()
  set(LOADED "${loaded}" PARENT_SCOPE)
  set(ERR "${err}" PARENT_SCOPE)
endfunction()

# The heavy libraries a log names: the loader writes "file=<name> [0];  needed by ..." for each library it looks
# for, and "calling init: <path>" for every object it initialises (a plugin dlopened by its path has only this).
function(heavy_in text result)
  string(REGEX MATCHALL "(file=|calling init: )[^ \n]*(${heavy})[^ \n]*" found "${text}")
  list(TRANSFORM found REPLACE "^(file=|calling init: )" "")
  list(REMOVE_DUPLICATES found)
  set(${result} "${found}" PARENT_SCOPE)
endfunction()

function(expect_light tag)
  run_logged(${tag} 0 ${ARGN})
  heavy_in("${LOADED}" found)
  if(found)
    list(JOIN found ", " found)
    message(FATAL_ERROR "fvm ${ARGN} loaded heavy libraries it does not use: ${found}\n"
                        "(load them through imaging/io/plugin_loader.h on first use of their format)")
  endif()
endfunction()

expect_light(version --version)
expect_light(calibrate calibrate ${SAMPLES}/bar17 --model 27 -o ${WORK}/cal.json)
expect_light(compare compare ${SAMPLES}/bar17 --json)
expect_light(diff diff ${SAMPLES}/stitching-strategies/x/a.csv ${SAMPLES}/stitching-strategies/x/b.csv)
expect_light(diagnose diagnose ${SAMPLES}/bar17 --model 27 --json)
expect_light(simulate simulate fvm-batch -o ${WORK}/sim --seed 1)
expect_light(simulate_tracker simulate tracker -o ${WORK}/tracker --seed 1)
expect_light(verify verify ${WORK}/tracker/readings.csv --tool 0,0,100 --order 2 -o ${WORK}/machine.json)
expect_light(simulate_stations simulate tracker -o ${WORK}/multi --seed 1 --stations ${SAMPLES}/stations/spread-4.json)
expect_light(multilaterate multilaterate ${WORK}/multi/readings.csv --stations ${WORK}/multi/stations.json -o ${WORK}/multi/p.csv)
expect_light(correct_machine correct --calibration ${WORK}/machine.json ${WORK}/tracker/points.csv -o ${WORK}/table.csv)

# Positive control: a TIFF loads the image plugin and OpenImageIO behind it, so the check above can fail.
run(0 tiles synthesize -o ${WORK}/tile --rows 1 --cols 1 --size 64 --bits 32 --seed 1)
file(GLOB tiffs ${WORK}/tile/*.tif)
list(GET tiffs 0 tiff)
run_logged(tiff 0 info ${tiff} --pixel-mm 0.001 --json)
heavy_in("${LOADED}" found)
if(NOT LOADED MATCHES "libfvm_image_oiio.so" OR NOT found MATCHES "libOpenImageIO")
  message(FATAL_ERROR "fvm info on a TIFF: the loader log names neither the image plugin nor OpenImageIO; "
                      "the check for light commands would pass whatever they load")
endif()

# Positive control: registering tiles loads the OpenCV plugin and OpenCV behind it.
run(0 tiles synthesize -o ${WORK}/pair --rows 1 --cols 2 --size 64 --bits 8 --seed 1)
run_logged(stitch 0 stitch --layout ${WORK}/pair/layout.csv --overlap 20 -o ${WORK}/pair/positions.csv)
heavy_in("${LOADED}" found)
if(NOT found MATCHES "libfvm_imaging_opencv.so" OR NOT found MATCHES "libopencv_core")
  message(FATAL_ERROR "fvm stitch: the loader log names neither the OpenCV plugin nor OpenCV (found: ${found}); "
                      "the check for light commands would pass whatever they load")
endif()

# Positive control: a report loads the report plugin and PLplot behind it.
run_logged(report 0 calibrate ${SAMPLES}/bar17 --model 27 -o ${WORK}/cal_report.json --report ${WORK}/report)
heavy_in("${LOADED}" found)
if(NOT found MATCHES "libfvm_report.so" OR NOT found MATCHES "libplplot" OR NOT EXISTS ${WORK}/report/index.html)
  message(FATAL_ERROR "fvm calibrate --report: no report, or the loader log names neither the report plugin nor "
                      "PLplot (found: ${found})")
endif()

# Without the plugin: the TIFF fails naming what is missing and what to install; an X3P still reads.
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
    <MatrixDimension><SizeX>2</SizeX><SizeY>1</SizeY><SizeZ>1</SizeZ></MatrixDimension>
    <DataList><Datum>1e-06</Datum><Datum>-2.5e-06</Datum></DataList>
  </Record3>
  <Record4><ChecksumFile>md5checksum.hex</ChecksumFile></Record4>
</p:ISO5436_2>
]=])
file(WRITE ${WORK}/x3p/main.xml "${xml}")
string(MD5 digest "${xml}")
file(WRITE ${WORK}/x3p/md5checksum.hex "${digest} *main.xml\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${WORK}/surface.x3p --format=zip main.xml md5checksum.hex
                WORKING_DIRECTORY ${WORK}/x3p RESULT_VARIABLE code)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "cannot zip the test X3P")
endif()

# Positive control: an X3P loads the plugin of the zip- and XML-based formats, and libzip, libcrypto and pugixml.
run_logged(x3p 0 info ${WORK}/surface.x3p --json)
heavy_in("${LOADED}" found)
if(NOT found MATCHES "libfvm_zip_xml_formats.so" OR NOT found MATCHES "libzip" OR NOT found MATCHES "libcrypto"
   OR NOT found MATCHES "libpugixml")
  message(FATAL_ERROR "fvm info on an X3P: the loader log does not name the zip and XML formats' plugin, libzip, "
                      "libcrypto and pugixml (found: ${found}); the check for light commands would pass whatever "
                      "they load")
endif()

execute_process(COMMAND ${CMAKE_COMMAND} -E env FVM_PLUGIN_DIR=${WORK}/no-plugins ${FVM} info ${tiff} --pixel-mm 0.001
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 1 OR NOT err MATCHES "reading [^\n]*\\.tif needs OpenImageIO: libfvm_image_oiio\\.so could not be loaded"
   OR NOT err MATCHES "install the Debian package libopenimageio")
  message(FATAL_ERROR "fvm info on a TIFF without the plugin: exit ${code}, expected 1 and a message naming the "
                      "plugin and the package to install, got:\n${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env FVM_PLUGIN_DIR=${WORK}/no-plugins ${FVM} focus ${WORK}/pair
                        -o ${WORK}/focus.x3p --pixel-mm 0.001
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 1 OR NOT err MATCHES "needs OpenCV: libfvm_imaging_opencv\\.so could not be loaded"
   OR NOT err MATCHES "install the Debian package libopencv" OR EXISTS ${WORK}/focus.x3p)
  message(FATAL_ERROR "fvm focus without the OpenCV plugin: exit ${code}, expected 1, no output and a message "
                      "naming the plugin and the package to install, got:\n${err}")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E env FVM_PLUGIN_DIR=${WORK}/no-plugins ${FVM} info ${WORK}/surface.x3p --json
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 1
   OR NOT err MATCHES "reading [^\n]*surface\\.x3p needs libzip and pugixml: libfvm_zip_xml_formats\\.so could not"
   OR NOT err MATCHES "install the Debian package libzip4")
  message(FATAL_ERROR "fvm info on an X3P without the plugin: exit ${code}, expected 1 and a message naming the "
                      "plugin and the package to install, got:\n${err}")
endif()
# A format that needs no plugin still reads without them.
file(WRITE ${WORK}/cloud.xyz "0 0 0\n1 0 0\n0 1 0.5\n")
execute_process(COMMAND ${CMAKE_COMMAND} -E env FVM_PLUGIN_DIR=${WORK}/no-plugins ${FVM} info ${WORK}/cloud.xyz --json
                RESULT_VARIABLE code OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT code EQUAL 0)
  message(FATAL_ERROR "fvm info on an XYZ cloud without the plugins: exit ${code}\n${err}")
endif()
string(JSON points GET "${out}" points)
if(NOT points EQUAL 3)
  message(FATAL_ERROR "fvm info on an XYZ cloud without the plugins: points ${points}, expected 3")
endif()
