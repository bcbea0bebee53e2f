# fvm focus as a user runs it: its help, and bad stacks that must fail with the file and line and leave no output
# (the height error on rendered stacks is in tests/imaging/focus_*_test.cc). Variables: FVM, WORK.

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

run(0 focus --help)
if(NOT OUT MATCHES "--measure" OR NOT OUT MATCHES "--min-quality" OR NOT OUT MATCHES "file,z_mm"
   OR NOT OUT MATCHES "--texture" OR NOT OUT MATCHES "--uncertainty" OR NOT OUT MATCHES "--z-step-mm"
   OR NOT OUT MATCHES "--align" OR NOT OUT MATCHES "--keep-end-peaks")
  message(FATAL_ERROR "fvm focus --help does not document its options:\n${OUT}")
endif()

# A stack of one image: refused from the list, before any image is read.
file(WRITE ${WORK}/one.csv "file,z_mm\nz0.png,0.0\n")
run(1 focus ${WORK}/one.csv -o ${WORK}/one.x3p)
if(NOT ERR MATCHES "one.csv: 1 image\\(s\\); a focus stack needs at least 3")
  message(FATAL_ERROR "one-image stack: unexpected message\n${ERR}")
endif()

# A list gives each image's z: a step with it is refused. Two images named directly are too few; an empty
# directory has none.
file(WRITE ${WORK}/three.csv "file,z_mm\na.png,0.0\nb.png,0.001\nc.png,0.002\n")
run(1 focus ${WORK}/three.csv -o ${WORK}/three.x3p --z-step-mm 0.001)
if(NOT ERR MATCHES "three.csv: the list gives each image's z")
  message(FATAL_ERROR "list with a step: unexpected message\n${ERR}")
endif()
run(1 focus ${WORK}/a.png ${WORK}/b.png -o ${WORK}/two.x3p)
if(NOT ERR MATCHES "2 image\\(s\\); a focus stack needs at least 3")
  message(FATAL_ERROR "two images: unexpected message\n${ERR}")
endif()
file(MAKE_DIRECTORY ${WORK}/empty)
run(1 focus ${WORK}/empty -o ${WORK}/empty.x3p)
if(NOT ERR MATCHES "empty: no image files")
  message(FATAL_ERROR "empty directory: unexpected message\n${ERR}")
endif()
run(1 focus ${WORK}/three.csv -o ${WORK}/three.x3p --uncertainty ${WORK}/u.txt)
if(NOT ERR MATCHES "u.txt: unknown output type")
  message(FATAL_ERROR "uncertainty output type: unexpected message\n${ERR}")
endif()

# Repeated and unsorted z positions name the line.
file(WRITE ${WORK}/repeat.csv "file,z_mm\na.png,0.0\nb.png,0.001\nc.png,0.001\n")
run(1 focus ${WORK}/repeat.csv -o ${WORK}/repeat.x3p)
if(NOT ERR MATCHES "repeat.csv:4: z = 0.001 mm repeats line 3")
  message(FATAL_ERROR "repeated z: unexpected message\n${ERR}")
endif()
file(WRITE ${WORK}/order.csv "file,z_mm\na.png,0.0\nb.png,0.002\nc.png,0.001\n")
run(1 focus ${WORK}/order.csv -o ${WORK}/order.x3p)
if(NOT ERR MATCHES "order.csv:4: .*out of order")
  message(FATAL_ERROR "unsorted z: unexpected message\n${ERR}")
endif()

# Images that are not there, or not images: the list's line and the file.
file(WRITE ${WORK}/missing.csv "file,z_mm\nnone0.png,0.0\nnone1.png,0.001\nnone2.png,0.002\n")
run(1 focus ${WORK}/missing.csv -o ${WORK}/missing.x3p)
if(NOT ERR MATCHES "missing.csv:2: .*none0.png")
  message(FATAL_ERROR "missing image: unexpected message\n${ERR}")
endif()

# Options: an unknown output type, an even window, an unknown measure.
run(1 focus ${WORK}/missing.csv -o ${WORK}/out.txt)
if(NOT ERR MATCHES "unknown output type")
  message(FATAL_ERROR "output type: unexpected message\n${ERR}")
endif()
run(1 focus ${WORK}/missing.csv -o ${WORK}/out.x3p --window 4)
if(NOT ERR MATCHES "odd number")
  message(FATAL_ERROR "even window: unexpected message\n${ERR}")
endif()
# A value outside the option's choices is a usage error (exit 2), found before any file is read.
run(2 focus ${WORK}/missing.csv -o ${WORK}/out.x3p --measure sharpness)

file(GLOB left ${WORK}/*.x3p ${WORK}/*.txt)
if(left)
  message(FATAL_ERROR "failed runs left output behind: ${left}")
endif()
