# ctest's start order on a clean clone (docs/CI.md, "ctest's order on a clean clone").
# `ctest -j2` starts the tests with the highest COST first; without Testing/Temporary/
# CTestCostData.txt (a clean clone) every test costs 0 and they start in the order they were
# declared, so a long one declared late runs alone at the end. These are the longest suites'
# seconds (one ctest test per GoogleTest suite: tests/test_suites.cmake) in stop 56's runs of
# both passes (2 cores, `ctest -j2`), per build; a later run's own times (the cost
# file) replace them. Included by ctest after the suites' tests (CMakeLists.txt sets PS_SANITIZE
# before including this); a name that no longer exists is ignored.
if(PS_SANITIZE)
  set(ps_test_costs
      TrackingOcclusion 43
      StressTracking 31
      StressReplay 29
      StressEdits 29
      SessionWriter 29
      IoImport 24
      SandOctahedral 23
      TrackingDetect 20
      TinSandTool 19
      TrackingChessboard 18
      TrackingCalibrate 16
      StressTinSand 16
      SandTubes 15
      LargeGrid 14
      StrokeTinRender 10)
else()
  set(ps_test_costs
      TrackingChessboard 15
      TrackingOcclusion 14
      StressReplay 14
      StressEdits 14
      SessionWriter 12
      LargeGrid 10
      TrackingFamilies 8
      StressTracking 8
      TrackingCalibrate 6
      IoImport 6)
endif()
list(LENGTH ps_test_costs ps_n)
math(EXPR ps_last "${ps_n} - 1")
foreach(ps_i RANGE 0 ${ps_last} 2)
  math(EXPR ps_j "${ps_i} + 1")
  list(GET ps_test_costs ${ps_i} ps_name)
  list(GET ps_test_costs ${ps_j} ps_cost)
  set_tests_properties(${ps_name} PROPERTIES COST ${ps_cost})
endforeach()
