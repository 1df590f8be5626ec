# cmake -DTOOLS=<dir with the tools> -DSOURCE=<project source> -DWORK=<scratch dir> -P tools_test.cmake
# Runs the tools as a user would: --help, a calibration scene through dps-synth and
# dps-calibrate, and bad inputs that must fail with a one-line message naming the problem.
file(REMOVE_RECURSE "${WORK}")
file(MAKE_DIRECTORY "${WORK}")

# expect(<exit: 0|nonzero> <regex that stdout+stderr must match> COMMAND ...)
function(expect want regex)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(want STREQUAL "0" AND NOT rc EQUAL 0)
    message(FATAL_ERROR "expected success: ${ARGN}\nexit ${rc}\n${out}\n${err}")
  elseif(want STREQUAL "nonzero" AND rc EQUAL 0)
    message(FATAL_ERROR "expected failure: ${ARGN}\n${out}\n${err}")
  endif()
  if(NOT "${out}${err}" MATCHES "${regex}")
    message(FATAL_ERROR "output of ${ARGN} does not match '${regex}':\n${out}\n${err}")
  endif()
  if(want STREQUAL "nonzero")
    string(STRIP "${err}" stripped)
    if(stripped MATCHES "\n")
      message(FATAL_ERROR "error of ${ARGN} is not one line:\n${err}")
    endif()
  endif()
  message(STATUS "ok: ${ARGN}")
endfunction()

foreach(tool dps-synth dps-calibrate)
  expect(0 "usage: ${tool}" "${TOOLS}/${tool}" --help)
  expect(nonzero "unknown option --bogus" "${TOOLS}/${tool}" --bogus)
endforeach()

expect(0 "wrote" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/calibration.yaml" --out "${WORK}/calib")
expect(nonzero "already exists" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/calibration.yaml" --out "${WORK}/calib")
expect(0 "rotation change from nominal" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --marks "${WORK}/calib/marks.csv" --out "${WORK}/calibrated.yaml")
if(NOT EXISTS "${WORK}/calibrated.yaml")
  message(FATAL_ERROR "dps-calibrate wrote no ${WORK}/calibrated.yaml")
endif()

# A randomised drive, and the parking lot seen by its rendering rig, calibrated from its rig.yaml.
expect(0 "wrote" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml" --randomize 1000 --size 320x240
       --frames 3 --out "${WORK}/random")
foreach(f rig.yaml rig_true.yaml randomization.json truth.csv)
  if(NOT EXISTS "${WORK}/random/${f}")
    message(FATAL_ERROR "dps-synth --randomize wrote no ${f}")
  endif()
endforeach()
expect(0 "wrote" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/calibration.yaml" --rig "${WORK}/random/rig_true.yaml"
       --processing-rig "${WORK}/random/rig.yaml" --frames 1 --out "${WORK}/random_calib")
expect(0 "rotation change from nominal" "${TOOLS}/dps-calibrate" --rig "${WORK}/random/rig.yaml"
       --marks "${WORK}/random_calib/marks.csv" --out "${WORK}/random_calibrated.yaml")
expect(nonzero "expected a non-negative integer" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml"
       --randomize -3 --out "${WORK}/random_bad")

# Automatic marks from the rendered images: marks file, drawings and a calibrated rig.
expect(0 "painted lines found" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --images "left=${WORK}/calib/left/000000.png,right=${WORK}/calib/right/000000.png"
       --write-marks "${WORK}/auto_marks.csv" --draw "${WORK}/auto_draw" --out "${WORK}/auto_calibrated.yaml")
foreach(f auto_marks.csv auto_draw/left_marks.png auto_draw/right_marks.png auto_calibrated.yaml)
  if(NOT EXISTS "${WORK}/${f}")
    message(FATAL_ERROR "dps-calibrate --images wrote no ${WORK}/${f}")
  endif()
endforeach()
expect(nonzero "expected CAMERA=IMAGE" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --images "${WORK}/calib/left/000000.png" --out "${WORK}/x.yaml")
expect(nonzero "nothing.png: cannot read the image" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --images "left=${WORK}/nothing.png" --out "${WORK}/x.yaml")
expect(nonzero "either --marks or --images" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --out "${WORK}/x.yaml")

file(WRITE "${WORK}/bad_marks.csv" "camera,line,u,v\nleft,1,10,10\n")
expect(nonzero "bad_marks.csv: missing column 'axis'" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --marks "${WORK}/bad_marks.csv" --out "${WORK}/x.yaml")
expect(nonzero "absent.csv: cannot open" "${TOOLS}/dps-calibrate" --rig "${WORK}/calib/rig.yaml"
       --marks "${WORK}/absent.csv" --out "${WORK}/x.yaml")
if(EXISTS "${WORK}/x.yaml")
  message(FATAL_ERROR "a failed dps-calibrate left ${WORK}/x.yaml behind")
endif()
file(WRITE "${WORK}/bad_scene.yaml" "%YAML:1.0\n---\nrig: ${SOURCE}/data/rigs/omni_pair.yaml\nfps: -1\n")
expect(nonzero "bad_scene.yaml: field 'fps'" "${TOOLS}/dps-synth" "${WORK}/bad_scene.yaml" --out "${WORK}/bad")
if(EXISTS "${WORK}/bad")
  message(FATAL_ERROR "a failed dps-synth left ${WORK}/bad behind")
endif()
file(REMOVE_RECURSE "${WORK}")

# A short drive through dps-process and dps-eval.
file(MAKE_DIRECTORY "${WORK}")
expect(0 "wrote" "${TOOLS}/dps-synth" "${SOURCE}/data/scenes/lead_car.yaml" --out "${WORK}/drives/lead" --size 320x240 --frames 8)
expect(0 "1 processed, 0 skipped, 0 failed" "${TOOLS}/dps-process" "${WORK}/drives/lead" --out "${WORK}/results")
expect(0 "skipped" "${TOOLS}/dps-process" "${WORK}/drives/lead" --out "${WORK}/results")
expect(0 "1 processed" "${TOOLS}/dps-process" "${WORK}/drives/lead" --out "${WORK}/diag" --diagnostics --map-png)
expect(0 "1 processed" "${TOOLS}/dps-process" "${WORK}/drives/lead" --out "${WORK}/remember" --remember --no-video)
if(NOT EXISTS "${WORK}/remember/lead/detections.csv")
  message(FATAL_ERROR "dps-process --remember wrote no detections.csv")
endif()
foreach(f diagnostics.avi diagnostics_middle.png map/000007.png)
  if(NOT EXISTS "${WORK}/diag/lead/${f}")
    message(FATAL_ERROR "dps-process --diagnostics --map-png wrote no ${WORK}/diag/lead/${f}")
  endif()
endforeach()
foreach(f detections.csv tracks.csv summary.json)
  if(NOT EXISTS "${WORK}/results/lead/${f}")
    message(FATAL_ERROR "dps-process wrote no ${WORK}/results/lead/${f}")
  endif()
endforeach()
expect(0 "band \\(m\\)" "${TOOLS}/dps-eval" --detections "${WORK}/results/lead/detections.csv"
       --truth "${WORK}/drives/lead/truth.csv" --rig "${WORK}/drives/lead/rig.yaml" --json "${WORK}/scores.json"
       --errors "${WORK}/errors.csv")
if(NOT EXISTS "${WORK}/scores.json")
  message(FATAL_ERROR "dps-eval wrote no --json file")
endif()
file(READ "${WORK}/errors.csv" errors)
if(NOT errors MATCHES "^frame,error,id,kind,x,z,range,cause,near_id,near_m\n")
  message(FATAL_ERROR "dps-eval --errors wrote no error list: ${errors}")
endif()
# --force redoes a complete drive; --list adds drives from a file; --shard I/N takes every N-th
# drive of the list from I, so two shards process each drive once between them.
expect(0 "1 processed, 0 skipped" "${TOOLS}/dps-process" "${WORK}/drives/lead" --out "${WORK}/results" --force)
# Off a terminal the progress is plain lines: frames, frames/s, the drive's and the batch's ETA.
expect(0 "drive 1/1 [^ ]*lead frame 8/8 \\([0-9.]+ frames/s, ETA 0 s, all 0 s\\)" "${TOOLS}/dps-process"
       "${WORK}/drives/lead" --out "${WORK}/results" --force)
file(COPY "${WORK}/drives/lead/" DESTINATION "${WORK}/drives/lead2")
file(WRITE "${WORK}/drives.txt" "${WORK}/drives/lead\n${WORK}/drives/lead2\n")
expect(0 "1 processed, 0 skipped, 0 failed" "${TOOLS}/dps-process" --list "${WORK}/drives.txt" --out "${WORK}/sharded"
       --shard 1/2)
if(EXISTS "${WORK}/sharded/lead" OR NOT EXISTS "${WORK}/sharded/lead2/summary.json")
  message(FATAL_ERROR "--shard 1/2 of two listed drives should process the second only")
endif()
expect(0 "1 processed, 0 skipped, 0 failed" "${TOOLS}/dps-process" --list "${WORK}/drives.txt" --out "${WORK}/sharded"
       --shard 0/2)
expect(0 "0 processed, 2 skipped, 0 failed" "${TOOLS}/dps-process" --list "${WORK}/drives.txt" --out "${WORK}/sharded")
# One bad drive among good ones: reported, the others finish, exit status = failures.
file(MAKE_DIRECTORY "${WORK}/drives/broken")
expect(nonzero "broken/rig.yaml: file not found" "${TOOLS}/dps-process" "${WORK}/drives/broken" "${WORK}/drives/lead"
       --out "${WORK}/results2" --quiet --jobs 2)
if(NOT EXISTS "${WORK}/results2/lead/summary.json")
  message(FATAL_ERROR "the good drive did not finish next to the broken one")
endif()
foreach(tool dps-process dps-eval dps-stereo)
  expect(0 "usage: ${tool}" "${TOOLS}/${tool}" --help)
endforeach()
expect(nonzero "missing --truth" "${TOOLS}/dps-eval" --detections x.csv)
expect(nonzero "missing --detections, --tracks or --lanes" "${TOOLS}/dps-eval" --truth x.csv)
file(REMOVE_RECURSE "${WORK}")
