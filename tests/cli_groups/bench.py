"""`cli_bench_<name>`: each benchmark's `--quick` run, its rows' fields and figures checked."""
import json
import math
import os

from cli_groups.common import BENCH, SRC, fail, run, out, is_png


def finite_numbers(x, where):
    if isinstance(x, dict):
        for k, v in x.items():
            finite_numbers(v, f"{where}.{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            finite_numbers(v, f"{where}[{i}]")
    elif isinstance(x, float) and not math.isfinite(x):
        fail(f"{where} is {x}")


BENCHES = ("bounds", "charts", "deform", "erosion", "export", "frame", "haptics", "live", "occlusion",
           "render", "roundtrip", "sand-tin", "sand-tin-charts", "tessellate", "track")


def check_bench_row(r):
    finite_numbers(r, r.get("bench", "?"))
    b = r.get("bench")
    # Peers (Martini, Delatin) promise no bound; this project's meshes guarantee theirs.
    if b in ("bounds", "export") and r.get("tool", "planetsculpt") == "planetsculpt" and \
            "requested_error_m" in r and "true_error_m" in r:
        if r["true_error_m"] > r["requested_error_m"] * (1 + 1e-9) or r.get("triangles", 1) <= 0:
            fail(f"{b}: true error {r['true_error_m']} over the requested {r['requested_error_m']}")
    tool = r.get("tool")
    if b == "export" and tool in ("planetsculpt-tin", "planet-tin") and \
            r["true_error_m"] > r["requested_error_m"] * (1 + 1e-9):
        fail(f"export {tool}: true error {r['true_error_m']} over the requested {r['requested_error_m']}")
    if b == "export" and tool == "planet-tin" and (r["euler"] != 2 or r["border_edges"] != 0):
        fail(f"export planet-tin: not a closed sphere: {r}")
    if b == "export" and tool == "control-map" and \
            r["measured_error_inside_m"] > r["min_error_m"] * (1 + 1e-9):
        fail(f"export control-map: {r['measured_error_inside_m']} m inside the control region")
    if b == "export" and tool == "overlay" and (r["euler"] != 1 or r.get("added_vertex_error_m", 0) > 1e-6
                                                or r.get("footprint_error_m", 0) > 1e-6
                                                or r.get("outside_error_ratio", 0) > 1 + 1e-9):
        fail(f"export overlay: {r}")
    if b == "export" and tool == "planet-overlay" and (
            r["euler"] != 2 or r["border_edges"] != 0 or r["non_manifold_edges"] != 0
            or r["added_vertex_error_m"] > 1e-6 or r["road_group_triangles"] <= 0
            or (r["stitch_in"] == "grid" and r["stitched_in"] != "grid")
            or (r["stitched_in"] == "road plane" and r["road_stray_m"] != 0)):
        fail(f"export planet-overlay: {r}")
    if b == "live" and r.get("saving") and (r["saves_done"] < 2 or r["records"] <= 0
                                           or r["saves_done"] > r["saves_started"]):
        fail(f"live: the session with saving on saved or journaled nothing: {r}")
    if b == "deform" and r.get("modified_vertices", 1) <= 0:
        fail(f"deform: no vertex modified in {r}")
    if b == "deform" and "modified_vertices" in r and r["modified_vertices"] != r["bruteforce_vertices"]:
        fail(f"deform: region growing is not brute force's set: {r}")
    # The octahedral chart's equal-area cells (docs/CHARTS.md): within a few percent.
    if b == "charts" and (r["cell_area_max_over_min"] < 1 or
                          (r["chart"] == "octahedral" and r["cell_area_max_over_min"] > 1.1)):
        fail(f"charts: cell areas {r}")
    # The tessellator's guarantee on every chart: the measured error never above dist_max.
    if b == "tessellate_chart" and (r["chart"] not in ("latlong", "octahedral") or r["triangles"] <= 0
                                    or r["max_screen_error_px"] > r["dist_max"] * (1 + 1e-9)):
        fail(f"tessellate_chart: {r}")
    # The press-only stroke (compare-exact) keeps no volume: its drift is null.
    exact = b == "sand-tin" and r.get("experiment") == "compare-exact"
    if b == "sand-tin" and (r.get("model") not in ("tin", "grid")
                            or (not exact and abs(r["volume_drift"]) > 1e-6)
                            or r["vertices"] <= 0 or r["memory_bytes"] <= 0 or r.get("valid", True) is not True):
        fail(f"sand-tin: {r}")
    # Against the exact shape: nothing differs away from the stroke, and the TIN's row carries
    # the grids' memory at its error.
    if exact and (r["surface_error_max_outside_band_m"] > 1e-9 or not r["surface_error_m"] > 0
                  or (r["model"] == "tin" and not 0 < r["memory_ratio_at_equal_error"] < 1e3)):
        fail(f"sand-tin compare-exact: {r}")
    # The TIN sand tool's same stamp on every chart: the grid's volume kept as on lat-long, the
    # same volume displaced (docs/SAND.md, "The TIN sand tool on the glued charts").
    if b == "sand-tin-charts" and (r["volume_drift"] > 1e-9 or r["grid_points"] <= 0 or r["tin_vertices"] <= 0
                                   or not r["displaced_m3"] > 0):
        fail(f"sand-tin-charts: {r}")
    # A DEM through each chart and back: errors ordered (rms <= max, p99 <= max), none zero.
    if b == "roundtrip" and not all(0 < r[f"{g}rms_m"] <= r["max_m"] and r[f"{g}p99_m"] <= r["max_m"]
                                    for g in ("", "polar_", "equator_", "north_", "south_")):
        fail(f"roundtrip: {r}")
    if b == "erosion" and abs(r.get("volume_drift", 0.0)) > 1e-6:
        fail(f"erosion: volume drift {r['volume_drift']}")
    for key in ("planet_detected", "control_vertex_within_3mm"):
        if b == "track" and key in r and not (0.0 <= r[key] <= 1.0):
            fail(f"track: {key} {r[key]} outside [0, 1]")
    # The hand mask's figures are fractions (iou -1: no frame with a hand in front).
    hand = b == "occlusion" and r.get("part") == "hand"
    if hand and not (r["iou"] == -1 or 0 <= r["iou"] <= 1) or \
            hand and not (0 <= r["hidden_by_mistake"] <= 1 and r["frames_with_pose"] > 0):
        fail(f"occlusion, the hand: {r}")
    if b == "render" and not r.get("skipped") and not (-1.0 <= r["ssim"] <= 1.0 and r["texture_bytes"] >= 0):
        fail(f"render: ssim {r['ssim']} or texture bytes {r['texture_bytes']} out of range")
    # Occlusion: IoUs and fractions are fractions, and the rows say which frames they cover.
    if b == "occlusion" and r.get("part") == "tool" and not r.get("skipped"):
        for key in ("iou", "iou_tool_tracked", "iou_frame_median", "iou_frame_min", "false_hidden",
                    "false_hidden_frame_max"):
            if key in r and not (0.0 <= r[key] <= 1.0):
                fail(f"occlusion {r['recording']}: {key} {r[key]} outside [0, 1]")
        if r["frames_tool_in_front"] + r["frames_nothing_in_front"] + r["frames_planet_lost"] != r["frames"]:
            fail(f"occlusion {r['recording']}: frame counts do not add up: {r}")
        if r["recording"].startswith("tool-") and "behind" not in r["recording"] and r["frames_tool_in_front"] == 0:
            fail(f"occlusion {r['recording']}: the tool never passed in front of the planet")
    for key, v in r.items():
        if (key == "ms" or key.endswith("_ms")) and isinstance(v, (int, float)) and v < 0:
            fail(f"{b}: {key} = {v} is negative")


def group_bench():
    # One benchmark (`bench_NAME`) with --quick: JSON rows that parse, finite numbers, the
    # figures that are exact (errors, counts) in their valid ranges, and its plots PNGs.
    name = BENCH
    if name not in BENCHES:
        fail(f"bench group needs one of {', '.join(BENCHES)}")
    dem = os.path.join(SRC, "..", "shared", "data", "dem", "mars_mola_1440x720_u16.png")
    if name == "roundtrip" and not os.path.exists(dem):
        print(f"cli bench roundtrip: skipped, {dem} is absent")
        return
    stdout, _ = run("bench", name, "--quick", "--out", out("bench"))
    rows = [json.loads(l) for l in stdout.splitlines() if l.startswith("{")]
    if not any(r.get("bench") == name for r in rows):
        fail(f"bench {name} --quick wrote no {name} row")
    for r in rows:
        check_bench_row(r)
    if name == "roundtrip" and sorted(r["chart"] for r in rows) != ["latlong", "octahedral"]:
        fail(f"bench roundtrip: not one row per chart: {rows}")
    # The sand core on the octahedral chart beside lat-long's in the same run (docs/SAND.md).
    if name == "erosion":
        for method in ("thermal", "diffusion-explicit", "diffusion-implicit", "crater-settle"):
            if not any(r.get("method") == method and r.get("chart") == "octahedral" for r in rows):
                fail(f"bench erosion wrote no octahedral {method} row")
        # The crater settled with the undo journal attached (the live configuration): undo
        # gives back the start bit for bit (docs/SAND.md, "Undo takes settling back").
        undone = [r for r in rows if r.get("method") == "crater-settle" and r.get("undo_journal")]
        if not undone or not all(r.get("undo_restores_start") is True for r in undone):
            fail(f"bench erosion: no crater row with the undo journal, or its undo did not restore: {undone}")
    if name == "sand-tin-charts":
        for chart in ("latlong", "octahedral", "torus", "cylinder"):
            if not any(r.get("chart") == chart for r in rows):
                fail(f"bench sand-tin-charts wrote no {chart} row")
        ref = next(r["displaced_m3"] for r in rows if r.get("chart") == "latlong")
        for r in rows:
            if not 0.95 < r["displaced_m3"] / ref < 1.05:
                fail(f"bench sand-tin-charts: the same stamp displaced otherwise than on lat-long: {r}")
    # Both parts of the occlusion bench (docs/BENCHMARKS.md): the tool's rows, then the hand's.
    if name == "occlusion" and not any(r.get("skipped") for r in rows):
        for part in ("tool", "hand"):
            if not any(r.get("part") == part for r in rows):
                fail(f"bench occlusion wrote no {part} row")
    # These benches run every case on both sphere charts in one run (issue 43, `--charts`'s
    # default): every row names its chart, and each chart has rows.
    if name in ("tessellate", "frame", "render") and not any(r.get("skipped") for r in rows):
        for r in rows:
            if r.get("chart") not in ("latlong", "octahedral"):
                fail(f"bench {name}: a row without its chart: {r}")
        for chart in ("latlong", "octahedral"):
            if not any(r.get("chart") == chart and r.get("bench") == name for r in rows):
                fail(f"bench {name} wrote no {chart} row")
    # The frame bench does what the live app does per frame, the hand mask included (its stage in
    # every row, on in the app's cases), and the demo case again with the mask off in the same
    # run: the same frames, the mask's stage spending nothing; with it on, the mask made in the
    # frames the planet's board is seen and its time counted in the frame's.
    if name == "frame" and not any(r.get("skipped") for r in rows):
        for chart in ("latlong", "octahedral"):
            cases = {r["case"]: r for r in rows if r.get("chart") == chart and "frames" in r}
            if set(cases) != {"demo", "demo_no_hand_mask", "demo_faceted", "dense"}:
                fail(f"bench frame {chart}: cases {sorted(cases)}")
            on, off = cases["demo"], cases["demo_no_hand_mask"]
            for case, r in cases.items():
                if r["frames"] != on["frames"] or r["frames"] <= 0 or r["tool_depth_pass"] is not True:
                    fail(f"bench frame {chart} {case}: {r['frames']} frames against demo's {on['frames']}")
                if r["hand_mask"] != (case != "demo_no_hand_mask") or "hand_mask" not in r["share"]:
                    fail(f"bench frame {chart} {case}: the hand mask's setting or share missing: {r}")
                if not (r["frame_ms"] > 0 and r["fps"] > 0 and 0 <= r["share"]["hand_mask"] < 1):
                    fail(f"bench frame {chart} {case}: times {r}")
                if abs(sum(r["share"].values()) - 1) > 0.01:
                    fail(f"bench frame {chart} {case}: the stages' shares do not add up to the frame: {r['share']}")
            # Off, the live loop's calls still run and return at once: microseconds, which a
            # preempted frame can round to a share of 0.001; a mask that ran costs 7-23 %.
            if off["hand_mask_masked_frames"] != 0 or off["hand_mask_shown_frames"] != 0 or \
                    off["share"]["hand_mask"] >= 0.01:
                fail(f"bench frame {chart}: the hand mask ran with it off: {off}")
            for case in ("demo", "demo_faceted", "dense"):
                r = cases[case]
                if not (0 < r["hand_mask_masked_frames"] <= r["planet_frames"] and r["hand_mask_ms"] > 0
                        and r["hand_mask_ms_mean_masked"] > 0 and r["share"]["hand_mask"] > 0
                        and r["hand_mask_shown_frames"] <= r["hand_mask_masked_frames"]
                        and (r["hand_mask_shown_frames"] == 0) == (r["hand_mask_shown_px"] == 0)):
                    fail(f"bench frame {chart} {case}: the hand mask did not run: {r}")
    # Per-pixel shading's claim (docs/RENDERING.md): a 4 px mesh shaded per pixel is closer to
    # the full-resolution surface than a 1 px mesh in facets, in every view, on every chart.
    rendered = [r for r in rows if r.get("bench") == "render" and not r.get("skipped")]
    for chart, view in {(r["chart"], r["view"]) for r in rendered}:
        at = {(r["shading"], r["dist_max_px"]): r for r in rendered if (r["chart"], r["view"]) == (chart, view)}
        if at[("per_pixel", 4.0)]["mean_abs_diff"] >= at[("faceted", 1.0)]["mean_abs_diff"]:
            fail(f"render {chart} {view}: per-pixel at 4 px is not closer to the reference than facets at 1 px")
    pngs = [n for n in os.listdir(out("bench")) if n.endswith(".png")] if os.path.isdir(out("bench")) else []
    if not all(is_png(out("bench", n)) for n in pngs):
        fail("bench --out wrote a plot that is not a PNG")
