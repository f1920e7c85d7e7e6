# ctest's start order on a clean clone (docs/CI.md, "ctest's order on a clean clone").
# `ctest -j2` starts the tests with the highest COST first; without Testing/Temporary/
# CTestCostData.txt (a clean clone) every test costs 0 and they start in the order they were
# declared, so a long one declared late runs alone at the end. These are the longest suites'
# seconds (one ctest test per GoogleTest suite: tests/test_suites.cmake) in stop 54's clean-clone
# run (2 cores; its tests' seconds summed by suite), per build; a later run's own times (the cost
# file) replace them. Included by ctest after the suites' tests (CMakeLists.txt sets PS_SANITIZE
# before including this); a name that no longer exists is ignored.
if(PS_SANITIZE)
  set(ps_test_costs
      TrackingOcclusion 97
      StressTracking 69
      IoImport 40
      TrackingDetect 36
      StressEdits 33
      StrokeTinRender 32
      SandOctahedral 31
      SandTubes 28
      SessionWriter 26
      StressReplay 25
      HandMask 25
      SessionTimeline 23
      ReplayStepper 22
      TinSandTool 21
      RenderShading 21)
else()
  set(ps_test_costs
      TrackingOcclusion 36
      TrackingChessboard 21
      StressEdits 18
      TrackingFamilies 17
      TrackingDetect 17
      SessionWriter 15
      StressTracking 15
      StressReplay 14
      IoImport 12
      LargeGrid 11)
endif()
list(LENGTH ps_test_costs ps_n)
math(EXPR ps_last "${ps_n} - 1")
foreach(ps_i RANGE 0 ${ps_last} 2)
  math(EXPR ps_j "${ps_i} + 1")
  list(GET ps_test_costs ${ps_i} ps_name)
  list(GET ps_test_costs ${ps_j} ps_cost)
  set_tests_properties(${ps_name} PROPERTIES COST ${ps_cost})
endforeach()
