#!/usr/bin/env python3
"""ctest cli_*: each `planetsculpt` command end to end on small inputs, its outputs checked.

Usage: cli_commands.py GROUP EXE SOURCE_DIR OUT_DIR [BENCH]
Groups (one module each under tests/cli_groups/): demo, import_export, road, charts, tube_charts,
synth_detect, markers, bench (with a benchmark's name), errors, openmp. (`live` has
live_smoke.sh; `calibrate` runs from ps_tests, TrackingCalibrate.CommandCalibratesAFolderOfRenderedViews,
which renders the views it reads.) Python's standard library only: the values are compared
through the raw float32 format, which needs no image decoder.
"""
import os
import shutil
import sys

sys.dont_write_bytecode = True  # nothing written into the source tree
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from cli_groups import bench, charts, demo, errors, import_export, openmp, tracking  # noqa: E402
from cli_groups.common import GROUP, OUT, fail  # noqa: E402

if __name__ == "__main__":
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    groups = {name[len("group_"):]: f for module in (demo, import_export, charts, tracking, bench, errors, openmp)
              for name, f in vars(module).items() if name.startswith("group_")}
    if GROUP not in groups:
        fail(f"unknown group {GROUP} (one of {', '.join(groups)})")
    groups[GROUP]()
    print(f"cli {GROUP}: passed")
