# The main job as a user runs it: calibrate the sample batch, correct a scan, compare the model orders, and the
# clear failures on bad input. Expects FVM, SAMPLES and WORK.
file(REMOVE_RECURSE ${WORK})
file(MAKE_DIRECTORY ${WORK})

include(${CMAKE_CURRENT_LIST_DIR}/cli_support.cmake)

# 1. Calibrate: the JSON holds every coefficient of the 27 model with its uncertainty, and the sample's first-order
#    truth is followed to the noise (0.5 um per coordinate in both measurements leaves ~1.2 um per centre).
run(0 calibrate ${SAMPLES}/bar17 --model 27 -o ${WORK}/cal.json --json)
string(JSON model GET "${OUT}" model)
string(JSON count LENGTH "${OUT}" parameters)
string(JSON u GET "${OUT}" parameters 0 u)
string(JSON after GET "${OUT}" validation mean_um)
string(JSON before GET "${OUT}" validation before mean_um)
if(NOT model STREQUAL "27" OR NOT count EQUAL 27 OR NOT u GREATER 0)
  message(FATAL_ERROR "calibrate JSON: model ${model}, ${count} parameters, u ${u}")
endif()
if(NOT after LESS 2.0 OR NOT before GREATER 50)
  message(FATAL_ERROR "calibrate: validation mean ${before} um before, ${after} um after")
endif()
# Judged first by what no frame changes, each figure beside its prediction; the sample's exports turn with the
# stage at their first tiles, and the 27 model's own rotation terms turn the first-tile figure with them.
expect_json_keys("calibrate" "${OUT}" validation/rigid/rms_um validation/rigid/max_um validation/rigid/predicted_rms_um
                 validation/distances/rms_um validation/distances/max_um validation/distances/predicted_rms_um
                 validation/predicted_rms_um validation/turn_coefficients frame_reference_mm)
string(JSON turn GET "${OUT}" validation turn)
string(JSON rigid GET "${OUT}" validation rigid rms_um)
string(JSON rigid_predicted GET "${OUT}" validation rigid predicted_rms_um)
string(JSON first_tile GET "${OUT}" validation rms_um)
string(JSON first_tile_predicted GET "${OUT}" validation predicted_rms_um)
# The targets: the rigid figure's prediction within 0.8-1.3 of it, the first tile's at least 0.8 of it (in nm:
# CMake's math has integers only).
foreach(v rigid rigid_predicted first_tile first_tile_predicted)
  scaled("${${v}}" 3 ${v}_nm)
endforeach()
math(EXPR rigid_low "${rigid_nm} * 8 / 10")
math(EXPR rigid_high "${rigid_nm} * 13 / 10")
math(EXPR first_tile_low "${first_tile_nm} * 8 / 10")
if(NOT turn MATCHES "^model$" OR rigid_predicted_nm LESS rigid_low OR rigid_predicted_nm GREATER rigid_high
   OR first_tile_predicted_nm LESS first_tile_low)
  message(FATAL_ERROR "calibrate: turn '${turn}', rigid ${rigid} um (predicted ${rigid_predicted}), first tile "
                      "${first_tile} um (predicted ${first_tile_predicted})")
endif()
file(READ ${WORK}/cal.json written)
string(JSON written_model GET "${written}" model)
if(NOT written_model STREQUAL "27")
  message(FATAL_ERROR "cal.json was not written as printed")
endif()

# 2. Correct a stitching-free export with that calibration.
run(0 correct --calibration ${WORK}/cal.json ${SAMPLES}/bar17/val-01.free.csv -o ${WORK}/val-01.corrected.csv)
file(STRINGS ${WORK}/val-01.corrected.csv lines)
list(FILTER lines EXCLUDE REGEX "^#")
list(GET lines 0 header)
list(LENGTH lines rows)
if(NOT header STREQUAL "id,x,y,z,u_x,u_y,u_z,t" OR NOT rows EQUAL 18)
  message(FATAL_ERROR "corrected export: header '${header}', ${rows} lines")
endif()

# The same export in its first tile's frame lands on the stitched export of the same placement (to the ~2 um of the
# validation); in the stage frame it differs from it by the stage's error at the first tile (tens of um).
function(centre_of file id result)
  file(STRINGS ${file} rows REGEX "^${id},")
  list(GET rows 0 row)
  string(REPLACE "," ";" fields "${row}")
  list(SUBLIST fields 1 3 xyz)
  set(${result} "${xyz}" PARENT_SCOPE)
endfunction()
function(distance_nm a b result)
  set(sum 0)
  foreach(k RANGE 2)
    list(GET a ${k} ak)
    list(GET b ${k} bk)
    scaled("${ak}" 6 an)
    scaled("${bk}" 6 bn)
    math(EXPR sum "${sum} + (${an} - (${bn})) * (${an} - (${bn}))")
  endforeach()
  set(${result} ${sum} PARENT_SCOPE)  # squared, nm^2
endfunction()
run(0 correct --calibration ${WORK}/cal.json ${SAMPLES}/bar17/val-01.free.csv -o ${WORK}/val-01.first-tile.csv --frame first-tile)
centre_of(${SAMPLES}/bar17/val-01.stitched.csv 17 stitched)
centre_of(${WORK}/val-01.first-tile.csv 17 first_tile)
centre_of(${WORK}/val-01.corrected.csv 17 stage_frame)
distance_nm("${first_tile}" "${stitched}" d_first)
distance_nm("${stage_frame}" "${stitched}" d_stage)
if(NOT d_first LESS 25000000 OR NOT d_stage GREATER 100000000)  # 5 um and 10 um, squared in nm
  message(FATAL_ERROR "calotte 17 of val-01: first-tile frame ${first_tile}, stage frame ${stage_frame}, stitched ${stitched}")
endif()

# 3. Compare the four orders: the contract keys, and the recommendation of a first-order model on first-order data.
run(0 compare ${SAMPLES}/bar17 --json)
string(JSON n LENGTH "${OUT}" models)
string(JSON id_rms GET "${OUT}" models 2 identification rms_um)
string(JSON val_max GET "${OUT}" models 2 validation max_um)
string(JSON aic GET "${OUT}" models 2 aic)
string(JSON cond GET "${OUT}" models 2 condition)
string(JSON recommendation GET "${OUT}" recommendation)
if(NOT n EQUAL 4 OR NOT recommendation MATCHES "^Use model 27")
  message(FATAL_ERROR "compare: ${n} models; recommendation: ${recommendation}")
endif()
# The sample's truth is first order with 0.5 um noise per coordinate in both measurements (samples/bar17/
# truth.json): a right model leaves sqrt(6) * 0.5 = 1.22 um rms per centre, less the ~15 fitted of 153 degrees of
# freedom (1.16 um), +-6 % for the draw (1.25 um observed). The largest of 170 held-out centres is about 3.5
# standard deviations of a 3-d residual (2.4 um observed); 4 um leaves room for the parameters' own uncertainty.
string(JSON aic9 GET "${OUT}" models 0 aic)
string(JSON aic15 GET "${OUT}" models 1 aic)
string(JSON aic42 GET "${OUT}" models 3 aic)
string(JSON cond42 GET "${OUT}" models 3 condition)
if(NOT id_rms GREATER 1.0 OR NOT id_rms LESS 1.5 OR NOT val_max GREATER 1.0 OR NOT val_max LESS 4.0)
  message(FATAL_ERROR "compare: model 27 leaves ${id_rms} um rms in identification, ${val_max} um at most in validation")
endif()
# The information criterion must prefer 27 by a margin the data give: 9 and 15 miss first-order terms worth tens
# of um (AIC hundreds higher), and 42's extra terms explain only noise (AIC no lower).
if(NOT aic LESS aic9 OR NOT aic LESS aic15 OR aic GREATER aic42)
  message(FATAL_ERROR "compare: AIC 9 ${aic9}, 15 ${aic15}, 27 ${aic}, 42 ${aic42}")
endif()
# The condition number (Jacobian in units of plausible coefficient sizes) is ~130 for 27 on this layout; an
# unresolved alias would send it past 1e6, and the second-order terms of 42 must make it worse, not better.
if(NOT cond GREATER 10 OR NOT cond LESS 1000 OR NOT cond42 GREATER cond)
  message(FATAL_ERROR "compare: condition number ${cond} for 27, ${cond42} for 42")
endif()

# 4. The sample batch is exactly what the simulator writes for seed 1 (same seed, same bytes).
run(0 simulate fvm-batch -o ${WORK}/sim --seed 1)
file(GLOB sample_files RELATIVE ${SAMPLES}/bar17 ${SAMPLES}/bar17/*)
foreach(f ${sample_files})
  file(SHA256 ${SAMPLES}/bar17/${f} a)
  file(SHA256 ${WORK}/sim/${f} b)
  if(NOT a STREQUAL b)
    message(FATAL_ERROR "samples/bar17/${f} differs from 'fvm simulate fvm-batch --seed 1'")
  endif()
endforeach()

# 5. Bad input: a clear message naming the file or calotte, non-zero exit, no output written.
file(COPY ${SAMPLES}/bar17/ DESTINATION ${WORK}/missing)
file(REMOVE ${WORK}/missing/id-y.free.csv)
fails_naming("id-y" calibrate ${WORK}/missing -o ${WORK}/missing.json)
if(EXISTS ${WORK}/missing.json)
  message(FATAL_ERROR "a failed calibrate left ${WORK}/missing.json behind")
endif()

file(MAKE_DIRECTORY ${WORK}/empty)
fails_naming("empty" calibrate ${WORK}/empty -o ${WORK}/empty.json)

file(MAKE_DIRECTORY ${WORK}/um)
file(WRITE ${WORK}/um/p.stitched.csv "id,x,y,z\n1,-150000,-100000,-50000\n2,-140000,-100000,-50000\n")
file(WRITE ${WORK}/um/p.free.csv "id,x,y,z\n1,-150000,-100000,-50000\n2,-140000,-100000,-50000\n")
fails_naming("micrometre" calibrate ${WORK}/um)

file(MAKE_DIRECTORY ${WORK}/few)
file(WRITE ${WORK}/few/p.stitched.csv "id,x,y,z\n1,-150,-100,-50\n2,-140,-100,-50\n3,-130,-100,-50\n")
file(WRITE ${WORK}/few/p.free.csv "id,x,y,z\n1,-150,-100,-50\n2,-140,-100,-50\n3,-130,-100,-50\n")
fails_naming("fewer than the 42" calibrate ${WORK}/few --model 42)

fails_naming("cal-missing.json" correct --calibration ${WORK}/cal-missing.json ${SAMPLES}/bar17/val-01.free.csv -o ${WORK}/x.csv)

# 6. Diagnose: the sample's exports turn with the stage at their first tiles, which only the held-out placements
#    show (frame_rotation, a yaw per placement); exports without the turn show nothing; a hidden drift is named,
#    with the held-out gap shrinking.
run(0 diagnose ${SAMPLES}/bar17 --model 27 --json)
string(JSON effect GET "${OUT}" effect)
string(JSON turns LENGTH "${OUT}" turns)
string(JSON unit GET "${OUT}" size unit)
if(NOT effect STREQUAL "frame_rotation" OR NOT turns EQUAL 10 OR NOT unit STREQUAL "urad")
  message(FATAL_ERROR "diagnose on the sample: ${effect}, ${turns} turns in ${unit}:\n${OUT}")
endif()
run(0 simulate fvm-batch -o ${WORK}/translated --seed 1 --stitched-frame translated)
run(0 diagnose ${WORK}/translated --model 27 --json)
string(JSON effect TYPE "${OUT}" effect)
if(NOT effect STREQUAL "NULL")
  message(FATAL_ERROR "diagnose named an effect on exports without the turn:\n${OUT}")
endif()
run(0 simulate fvm-batch -o ${WORK}/drift --seed 7 --hidden-effect thermal_drift)
run(0 diagnose ${WORK}/drift --model 27 --json --report ${WORK}/drift-report)
string(JSON effect GET "${OUT}" effect)
string(JSON first_step GET "${OUT}" effects 0 effect)
if(NOT first_step STREQUAL effect)
  message(FATAL_ERROR "diagnose: 'effect' ${effect} is not the first of 'effects' (${first_step})")
endif()
string(JSON before GET "${OUT}" validation before mean_um)
string(JSON after GET "${OUT}" validation after mean_um)
if(NOT effect STREQUAL "thermal_drift" OR NOT EXISTS ${WORK}/drift-report/index.html OR NOT after LESS 2.5
   OR NOT before GREATER 5)
  message(FATAL_ERROR "diagnose on a drifting batch: ${effect}, held-out mean ${before} -> ${after} um")
endif()
file(READ ${WORK}/drift-report/index.html page)
if(NOT EXISTS ${WORK}/drift-report/steps.svg OR NOT page MATCHES "steps.svg")
  message(FATAL_ERROR "diagnose --report: no plot of the steps")
endif()

# Several effects at once: both named, in the order they were added.
run(0 simulate fvm-batch -o ${WORK}/two --seed 1 --hidden-effect thermal_drift,outliers --stitched-frame translated)
run(0 diagnose ${WORK}/two --model 27 --json)
expect_json_keys("diagnose" "${OUT}" effects/1/effect effects/1/size/unit effects/1/validation/after/mean_um)
string(JSON steps LENGTH "${OUT}" effects)
string(JSON e0 GET "${OUT}" effects 0 effect)
string(JSON e1 GET "${OUT}" effects 1 effect)
if(NOT steps EQUAL 2 OR NOT "${e0};${e1}" MATCHES "outliers" OR NOT "${e0};${e1}" MATCHES "thermal_drift")
  message(FATAL_ERROR "diagnose with a drift and outliers named: ${e0}, ${e1} (${steps} steps)")
endif()
# A base model of one's own: the 15 model's constant terms without pitch and roll, on a wedge measured serpentine,
# shows both a scale and pitch and roll (the 9 model's linear terms would take the scale).
set(terms "xTx:0,xTy:0,xTz:0,yTx:0,yTy:0,yTz:0,xRz:0,yRz:0,xWy:0,xWz:0,yWz:0")
run(0 simulate fvm-batch -o ${WORK}/custom --seed 2 --truth-terms ${terms} --hidden-effect z_coupling,scale
    --height-step-mm 20 --serpentine --stitched-frame translated)
file(READ ${WORK}/custom/truth.json truth)
string(JSON model GET "${truth}" model)
string(JSON serpentine GET "${truth}" serpentine)
run(0 diagnose ${WORK}/custom --terms ${terms} --json)
string(JSON e0 GET "${OUT}" effects 0 effect)
string(JSON e1 GET "${OUT}" effects 1 effect)
string(JSON diagnosed GET "${OUT}" model)
if(NOT "${e0};${e1}" MATCHES "scale" OR NOT "${e0};${e1}" MATCHES "z_coupling" OR NOT model STREQUAL "terms:${terms}"
   OR NOT diagnosed STREQUAL model OR NOT serpentine STREQUAL "ON")
  message(FATAL_ERROR "diagnose --terms on a serpentine wedge: ${e0}, ${e1}; truth ${model} (${serpentine}), diagnosed ${diagnosed}")
endif()
fails_naming("unknown hidden effect 'bogus'" simulate fvm-batch -o ${WORK}/bogus --hidden-effect thermal_drift,bogus)
fails_naming("--height-step-mm" simulate fvm-batch -o ${WORK}/wedge --height-step-mm -1)

# 7. The published stitching strategies under the calibrated stage: a is exact, b = e = f is the whole error of
#    the row, and c < d grow with the distance to the last tile placed by the encoders.
run(0 tiles simulate --calibration ${WORK}/cal.json --json)
foreach(k RANGE 5)
  string(JSON d GET "${OUT}" cases ${k} diff_um)
  string(SUBSTRING "abcdef" ${k} 1 id)
  string(REGEX REPLACE "^-" "" abs_${id} "${d}")
endforeach()
expect_near("case a" ${abs_a} 0 0.0001)
expect_near("case e vs b" ${abs_e} ${abs_b} 0.0001)
expect_near("case f vs b" ${abs_f} ${abs_b} 0.0001)
if(NOT abs_c LESS abs_d OR NOT abs_d LESS abs_b OR NOT abs_b GREATER 1)
  message(FATAL_ERROR "strategy errors out of the published order: c ${abs_c}, d ${abs_d}, b ${abs_b} um")
endif()

# 8. The same on rendered tiles: case a is off only by the registration (0.006 px rms of 6.3 um pixels over 16
#    pairs: well under 1 um), b keeps the whole error, and the row, written out, stitches with fvm stitch.
run(0 tiles simulate --calibration ${WORK}/cal.json --render --tile-px 256 --tiles ${WORK}/row --json)
string(JSON a GET "${OUT}" cases 0 rendered diff_um)
string(JSON b GET "${OUT}" cases 1 rendered diff_um)
string(JSON b_coordinates GET "${OUT}" cases 1 diff_um)
string(REGEX REPLACE "^-" "" a "${a}")
expect_near("rendered case a" ${a} 0 1.0)
expect_near("rendered case b" ${b} ${b_coordinates} 0.1)
run(0 stitch --layout ${WORK}/row/layout.csv --overlap 20 --pixel-mm 0.006328125 -o ${WORK}/row/positions.csv --json)
string(JSON accepted GET "${OUT}" pairs_accepted)
if(NOT accepted EQUAL 16)
  message(FATAL_ERROR "the rendered row stitched with ${accepted} of 16 pairs")
endif()
