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
