# Lists ps_tests' GoogleTest suites after each build and writes one ctest test per suite
# (`ps_tests --gtest_filter=Suite.*`), which ctest includes (CMakeLists.txt). One process per
# suite rather than per test: each ps_tests process pays the dynamic loader's binding of the 258
# libraries OpenCV's and GDAL's packages pull in and, under the sanitizers, their start and exit
# (docs/CI.md, "One process per suite, shared headers": the ASan pass's tests 618 -> 351 s). A
# failing suite's output names the failing test. Suites named Stress* carry the `stress` label and
# a timeout that grows with PS_STRESS_SCALE (read when ctest runs); the others `unit`. Every test
# runs with ENV.
# Usage: cmake -DEXE=ps_tests -DOUT=file.cmake -DENV=VAR=value -P test_suites.cmake
execute_process(COMMAND ${EXE} --gtest_list_tests OUTPUT_VARIABLE listing
                RESULT_VARIABLE rc ERROR_VARIABLE errors TIMEOUT 120)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${EXE} --gtest_list_tests failed (${rc}): ${errors}")
endif()
string(REPLACE "\n" ";" lines "${listing}")
set(suites "")
foreach(line IN LISTS lines)
  # A suite's line starts in column 0 and ends its name with a dot ("Suite." or
  # "Prefix/Suite.  # TypeParam = ..."); its tests' lines are indented.
  if(line MATCHES "^([A-Za-z0-9_/]+)\\.")
    list(APPEND suites ${CMAKE_MATCH_1})
  endif()
endforeach()
list(LENGTH suites count)
if(count LESS 50)
  message(FATAL_ERROR "${EXE} --gtest_list_tests named only ${count} suites: ${listing}")
endif()
string(CONCAT text
       "# Written by tests/test_suites.cmake after each build of ps_tests.\n"
       "set(ps_stress_scale 1)\n"
       "if(\"\$ENV{PS_STRESS_SCALE}\" MATCHES \"^[1-9][0-9]*$\")\n"
       "  set(ps_stress_scale \$ENV{PS_STRESS_SCALE})\n"
       "endif()\n"
       "math(EXPR ps_stress_timeout \"900 * \${ps_stress_scale}\")\n")
foreach(suite IN LISTS suites)
  if(suite MATCHES "^Stress")
    set(properties "LABELS stress TIMEOUT \${ps_stress_timeout}")
  else()
    set(properties "LABELS unit")
  endif()
  string(APPEND text "add_test([=[${suite}]=] [==[${EXE}]==] [=[--gtest_filter=${suite}.*]=])\n"
                     "set_tests_properties([=[${suite}]=] PROPERTIES ${properties} "
                     "ENVIRONMENT [=[${ENV}]=])\n")
endforeach()
file(WRITE ${OUT}.new "${text}")
file(RENAME ${OUT}.new ${OUT})
