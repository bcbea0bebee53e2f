# fvm multilaterate as a user runs it: fvm simulate tracker --stations makes the readings of a simulated machine
# from four stations, fvm multilaterate locates the points with the stations known and self-calibrated, with and
# without the angles, its points feed fvm verify, and bad input stops with a message naming the point or station.
# Variables: FVM (the executable), WORK (a scratch directory).

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

# Four stations spread around the published 2500 x 1500 x 1200 mm machine (machine frame, mm).
file(WRITE ${WORK}/stations.json [=[
{"stations": [{"name": "A", "x": 1250, "y": -1699, "z": -1132},
              {"name": "B", "x": 3371, "y": 1975, "z": -1132},
              {"name": "C", "x": -871, "y": 1975, "z": -1132},
              {"name": "D", "x": -1309, "y": -727, "z": 1121}]}
]=])
run(0 simulate tracker --seed 1 --tool 0,0,100 --stations ${WORK}/stations.json --validation mesh:500,500,400 -o ${WORK}/net)
if(NOT OUT MATCHES "read by 4 stations" OR NOT EXISTS ${WORK}/net/true_points.csv OR NOT EXISTS ${WORK}/net/stations.json)
  message(FATAL_ERROR "simulate tracker --stations:\n${OUT}")
endif()
file(STRINGS ${WORK}/net/readings.csv rows REGEX "^P[0-9]")
list(LENGTH rows count)
if(NOT count EQUAL 384)
  message(FATAL_ERROR "readings.csv has ${count} rows, expected 96 points x 4 stations")
endif()

# Known stations, ranges only: the points within a few tens of um of the truth, the JSON contract.
run(0 multilaterate ${WORK}/net/readings.csv --stations ${WORK}/net/stations.json -o ${WORK}/points.csv
    --verify-readings ${WORK}/ml.csv --truth ${WORK}/net/true_points.csv --json)
expect_json_keys("fvm multilaterate" "${OUT}" points stations range_rms_um geometry unobservable truth_error)
string(JSON n LENGTH "${OUT}" points)
string(JSON name GET "${OUT}" stations 3 name)
string(JSON err GET "${OUT}" truth_error mean_um)
string(JSON u GET "${OUT}" u_mean_um)
if(NOT n EQUAL 96 OR NOT name STREQUAL "D")
  message(FATAL_ERROR "points ${n}, fourth station ${name}")
endif()
expect_near("mean error against the truth (um)" "${err}" 12 8 1)
expect_near("mean 3D uncertainty (um)" "${u}" 12 8 1)
file(STRINGS ${WORK}/points.csv header REGEX "^id,")
if(NOT header STREQUAL "id,x,y,z,u_x,u_y,u_z")
  message(FATAL_ERROR "points.csv header: ${header}")
endif()

# The points feed fvm verify (id,x,y,z,xt,yt,zt in the stations' frame); validation.csv is in the same frame.
run(0 verify ${WORK}/ml.csv --tool 0,0,100 --unweighted --validate ${WORK}/net/validation.csv --json)
string(JSON vpoints GET "${OUT}" points)
string(JSON vfinal GET "${OUT}" validation final mean_um)
if(NOT vpoints EQUAL 96)
  message(FATAL_ERROR "fvm verify read ${vpoints} points")
endif()
expect_near("validation mean after verify (um)" "${vfinal}" 15 15 1)

# Self-calibration, started from the angles, then with the angles too: the stations found within 0.2 mm.
foreach(extra "" "--angles")
  run(0 multilaterate ${WORK}/net/readings.csv --self-calibrate ${extra} --truth ${WORK}/net/true_points.csv --json)
  string(JSON bx GET "${OUT}" stations 1 x)
  string(JSON err GET "${OUT}" truth_error mean_um)
  file(READ ${WORK}/net/stations.json truth)
  string(JSON tx GET "${truth}" stations 1 x)
  expect_near("self-calibrated station B x ${extra}" "${bx}" "${tx}" 0.2)
  expect_near("self-calibrated mean error ${extra} (um)" "${err}" 20 20 1)
endforeach()
run(0 multilaterate ${WORK}/net/readings.csv --self-calibrate --stations ${WORK}/stations.json)
if(NOT OUT MATCHES "self-calibrated" OR NOT OUT MATCHES "station A: 0.0000, 0.0000, 0.0000 mm \\(held\\)")
  message(FATAL_ERROR "self-calibration summary:\n${OUT}")
endif()

# Three stations: self-calibration names the three directions it cannot determine.
file(WRITE ${WORK}/three.json [=[
{"stations": [{"name": "A", "x": 1250, "y": -1699, "z": -1132},
              {"name": "B", "x": 3371, "y": 1975, "z": -1132},
              {"name": "C", "x": -871, "y": 1975, "z": -1132}]}
]=])
run(0 simulate tracker --seed 2 --stations ${WORK}/three.json -o ${WORK}/three)
fails_naming("3 direction\\(s\\).*station B x.*station C x.*station C y"
             multilaterate ${WORK}/three/readings.csv --self-calibrate --stations ${WORK}/three/stations.json)
run(0 multilaterate ${WORK}/three/readings.csv --stations ${WORK}/three/stations.json)

# Bad input: the point, the station or the geometry named, exit 1, nothing written.
file(WRITE ${WORK}/two.csv "id,station,range\nP2,A,3000\nP2,B,3100\nP2,C,3200\nP1,A,3000\nP1,B,3100\n")
fails_naming("point P1 is seen by 2 station" multilaterate ${WORK}/two.csv --stations ${WORK}/three.json -o ${WORK}/bad.csv)
file(WRITE ${WORK}/nostation.csv "id,station,range\nP1,A,3000\nP1,B,3100\nP1,E,2000\n")
fails_naming("nostation.csv:4: point P1: station E is not in" multilaterate ${WORK}/nostation.csv --stations ${WORK}/three.json -o ${WORK}/bad.csv)
file(WRITE ${WORK}/silent.csv "id,station,range\nP1,A,3000\nP1,B,3100\nP1,D,2000\n")
fails_naming("station C has no readings" multilaterate ${WORK}/silent.csv --stations ${WORK}/stations.json -o ${WORK}/bad.csv)
file(WRITE ${WORK}/flat.json [=[{"stations": [{"name": "A", "x": 0, "y": 0, "z": 0}, {"name": "B", "x": 1000, "y": 0, "z": 0}, {"name": "C", "x": 0, "y": 1000, "z": 0}]}]=])
file(WRITE ${WORK}/flat.csv "id,station,range\nP1,A,500\nP1,B,806.225774829855\nP1,C,670.820393249937\n")
fails_naming("point P1 cannot be located: it lies in one plane" multilaterate ${WORK}/flat.csv --stations ${WORK}/flat.json -o ${WORK}/bad.csv)
file(WRITE ${WORK}/negative.csv "# a comment\nid,station,range\nP1,A,-3\n")
fails_naming("negative.csv:3: point P1, station A: range = -3 mm" multilaterate ${WORK}/negative.csv --stations ${WORK}/three.json)
file(WRITE ${WORK}/noangles.csv "id,station,range\nP1,A,3000\n")
fails_naming("--angles needs azimuth,elevation" multilaterate ${WORK}/noangles.csv --stations ${WORK}/three.json --angles)
file(WRITE ${WORK}/plain.csv "id,station,range\nP1,A,707.1067811865476\nP1,B,948.6832980505138\nP1,C,836.6600265340756\n")
run(0 multilaterate ${WORK}/plain.csv --stations ${WORK}/flat.json --json)
string(JSON pz GET "${OUT}" points 0 z)
expect_near("z of a point above three stations (mm)" "${pz}" 500 0.000001 6)
fails_naming("needs each point's nominal" multilaterate ${WORK}/plain.csv --stations ${WORK}/flat.json --verify-readings ${WORK}/bad.csv)
file(WRITE ${WORK}/broken.json "{\"stations\": [{\"name\": \"A\", \"x\": 0, \"y\": 0}]}")
fails_naming("broken.json: stations\\[0\\]: station A: no number \"z\"" multilaterate ${WORK}/two.csv --stations ${WORK}/broken.json)
if(EXISTS ${WORK}/bad.csv)
  message(FATAL_ERROR "a refused run wrote its output")
endif()
