# ctest's start order on a clean clone (docs/CI.md, "ctest's order on a clean clone").
# `ctest -j2` starts the tests with the highest COST first; without Testing/Temporary/
# CTestCostData.txt (a clean clone) every test costs 0 and they start in the order they were
# declared, so a long one declared late runs alone at the end. These are the longest tests'
# seconds in stop 48's clean-clone run (2 cores), per build; a later run's own times (the cost
# file) replace them. Included by ctest after the discovered GoogleTest tests (CMakeLists.txt sets
# PS_SANITIZE before including this); a name that no longer exists is ignored.
if(PS_SANITIZE)
  set(ps_test_costs
      SessionWriter.SigkillDuringBackgroundSavesRecoversAPlanetTheSessionHad 25
      TrackingOcclusion.ACoveredBoardIsCarriedByTheTableWhileTheCameraMoves 23
      TrackingOcclusion.ACoveredBoardOnAPlainTableIsLostNotDrawnWrong 22
      StressEdits.RandomBrushActionsOnTheOctahedralChartKeepEveryInvariant 22
      StressEdits.RandomActionsOfEveryToolKeepEveryInvariant 18
      StressReplay.LongReplayKeepsMemoryFlat 18
      TrackingDetect.CoarseRegionSearchOnlyWhereABoxHoldsManyMarkers 16
      IoImport.RealMarsRoundTripIsAsStated 15
      IoImport.RealMarsRoundTripOnTheOctahedralChart 13
      LargeGrid.Grid8193ViewsAreCrackFreeAndWithinDistMax 12
      TrackingFamilies.BoardAndToolOfTwoFamiliesTrackTogether 11
      StrokeTinRender.ThePatchsPerPixelLightIsItsFacetsSlope 11
      StrokeTinRender.InsideTheRegionTheDepthIsTheTinSurfaceNotTheGrids 11
      TrackingUndistort.ThePlanetsAnchorLandsOnItsMarkerThroughADistortingLens 9)
else()
  set(ps_test_costs
      TrackingChessboard.CommandCalibratesAFolderOfRenderedViews 11
      SessionWriter.SigkillDuringBackgroundSavesRecoversAPlanetTheSessionHad 33
      StressReplay.LongReplayKeepsMemoryFlat 14
      LargeGrid.Grid8193ViewsAreCrackFreeAndWithinDistMax 13
      TrackingOcclusion.ACoveredBoardOnAPlainTableIsLostNotDrawnWrong 10
      TrackingOcclusion.ACoveredBoardIsCarriedByTheTableWhileTheCameraMoves 9
      StressEdits.RandomActionsOfEveryToolKeepEveryInvariant 9
      StressEdits.RandomBrushActionsOnTheOctahedralChartKeepEveryInvariant 9
      TrackingDetect.CoarseRegionSearchOnlyWhereABoxHoldsManyMarkers 6)
endif()
list(LENGTH ps_test_costs ps_n)
math(EXPR ps_last "${ps_n} - 1")
foreach(ps_i RANGE 0 ${ps_last} 2)
  math(EXPR ps_j "${ps_i} + 1")
  list(GET ps_test_costs ${ps_i} ps_name)
  list(GET ps_test_costs ${ps_j} ps_cost)
  set_tests_properties(${ps_name} PROPERTIES COST ${ps_cost})
endforeach()
