"""`cli_charts` and `cli_tube_charts`: every command on the octahedral chart, the torus and the
cylinder."""
import json
import math
import os
import struct
import subprocess

from cli_groups.common import CALIB, EXE, SRC, fail, run, out, is_png


def group_charts():
    # A new planet on the octahedral chart (`--chart`, and the default without it): the demo's
    # first 90 frames replayed onto it with and without `--chart octahedral` give the same
    # planet file bit for bit (a version 2 file that names its chart), the summary says which
    # chart, and the brush sculpted it.
    video = os.path.join(SRC, "data", "demo.mkv")
    for k, chart in (("a", ("--chart", "octahedral")), ("b", ())):
        run("replay", video, "--calib", CALIB, *chart, "--grid", "1025",
            "--max-frames", "90", "--out", out(f"octa_{k}"))
    with open(out("octa_a", "summary.json")) as f:
        s = json.load(f)
    if s["chart"] != "octahedral" or s["grid"] != "1025x1025" or s["modified_vertices"] <= 0 or s["strokes"] < 1:
        fail(f"the octahedral replay: {s}")
    a = open(out("octa_a", "planet.planet"), "rb").read()
    if a != open(out("octa_b", "planet.planet"), "rb").read():
        fail("replays with --chart octahedral and without --chart wrote different planet files")
    if struct.unpack("<I", a[8:12])[0] != 2 or not a[16:32].startswith(b"octahedral\0"):
        fail(f"the octahedral planet file's header: {a[:32]!r}")
    # A planet file keeps its chart under the octahedral default: a lat-long planet (a version 1
    # file) replayed with --planet and no --chart stays lat-long.
    run("replay", video, "--calib", CALIB, "--chart", "latlong", "--grid", "257", "--max-frames", "5",
        "--out", out("ll"))
    ll = open(out("ll", "planet.planet"), "rb").read()
    if struct.unpack("<I", ll[8:12])[0] != 1:
        fail(f"the lat-long planet file's header: {ll[:32]!r}")
    run("replay", video, "--calib", CALIB, "--planet", out("ll", "planet.planet"), "--max-frames", "5",
        "--out", out("ll_again"))
    with open(out("ll_again", "summary.json")) as f:
        s = json.load(f)
    if s["chart"] != "latlong":
        fail(f"a lat-long planet file replayed onto {s['chart']}")
    # Its heightmap export is the whole sphere (equirectangular through the chart's inverse).
    meta = json.load(open(out("octa_a", "heightmap.png.json")))
    if meta.get("projection", "").find("equirectangular") < 0:
        fail(f"the octahedral replay's heightmap sidecar: {meta}")
    # The sand tool (displacement, the settler after it) and the haptic force path work on the
    # octahedral chart: the same planet twice, sand displaced and settled, forces written.
    for k in ("a", "b"):
        run("replay", video, "--calib", CALIB, "--chart", "octahedral", "--grid", "1025",
            "--max-frames", "90", "--tool", "displace", "--out", out(f"octa_sand_{k}"))
    with open(out("octa_sand_a", "summary.json")) as f:
        s = json.load(f)
    if (s["chart"] != "octahedral" or s["tool"] != "displace" or s["stamps"] <= 0 or s["settle_cell_steps"] <= 0
            or s.get("force_ticks", 0) <= 0 or "forces.csv" not in s["files"]):
        fail(f"the octahedral sand replay: {s}")
    if open(out("octa_sand_a", "planet.planet"), "rb").read() != open(out("octa_sand_b", "planet.planet"), "rb").read():
        fail("two sand replays onto the octahedral planet wrote different planet files")
    # The same frames pressed deeper (walls steeper than sand's 30 degrees on these 4 km cells),
    # in sand and in pebbles (--material), which hold 60: the same stamps, another planet.
    deep = {}
    for material in ("sand", "pebbles"):
        run("replay", video, "--calib", CALIB, "--chart", "octahedral", "--grid", "1025", "--max-frames", "90",
            "--tool", "displace", "--press-m", "30000", "--material", material, "--out", out(f"octa_{material}"))
        with open(out(f"octa_{material}", "summary.json")) as f:
            deep[material] = json.load(f)
    if [deep[m]["material"] for m in deep] != ["sand", "pebbles"] or deep["sand"]["stamps"] != deep["pebbles"]["stamps"]:
        fail(f"the sand and pebbles replays: {deep}")
    if open(out("octa_sand", "planet.planet"), "rb").read() == open(out("octa_pebbles", "planet.planet"), "rb").read():
        fail("pebbles and sand left the same planet")
    # The TIN sand tool on the octahedral chart (issue 43): its region TIN drawn in the AR view,
    # stamps written back, forces felt.
    run("replay", video, "--calib", CALIB, "--chart", "octahedral", "--grid", "513", "--max-frames", "60",
        "--tool", "tin-sand", "--render", "--render-every", "15", "--out", out("octa_tin"))
    with open(out("octa_tin", "summary.json")) as f:
        s = json.load(f)
    if (s["chart"] != "octahedral" or s["tool"] != "tin-sand" or s["stamps"] <= 0
            or s["modified_vertices"] <= 0 or s.get("ar_stroke_tin_frames", 0) < 1):
        fail(f"the octahedral TIN sand replay: {s}")
    # Refusals, named: an unknown chart, --chart with a planet file (it has its own).
    for args, said in ((("--chart", "cube"), "chart 'cube' is not one of"),
                       (("--material", "clay"), "material 'clay' is not one of sand, mud, pebbles"),
                       (("--chart", "octahedral", "--planet", out("octa_a", "planet.planet")), "has its own chart")):
        p = subprocess.run([EXE, "replay", video, "--calib", CALIB, "--grid", "1025", "--max-frames", "5", *args,
                            "--out", out("refused")], capture_output=True, text=True)
        if p.returncode <= 0 or said not in p.stderr:
            fail(f"replay {' '.join(args)} was not refused saying '{said}': {p.returncode} {p.stderr}")


def group_tube_charts():
    # A torus and a cylinder planet stand on the planet board (issue 28): the demo's frames
    # through its second stroke (frames 160-225, over the default sphere's 5-15 degrees N, where
    # the default torus's outer equator and the default cylinder's band are) replayed onto each
    # sculpt it; the planet file keeps its dimensions, the heightmap is its own (u, v) grid
    # (import takes it back), the pictures are written. Twice onto the torus: the same file.
    video = os.path.join(SRC, "data", "demo.mkv")
    for name, args in (("torus_a", ("--chart", "torus")), ("torus_b", ("--chart", "torus")),
                       ("tube", ("--chart", "cylinder", "--radius", "6000000", "--length", "4000000"))):
        extra = ("--pictures",) if name != "torus_b" else ()
        run("replay", video, "--calib", CALIB, *args, "--grid", "257", "--max-frames", "230",
            *extra, "--out", out(name))
    for name, chart in (("torus_a", "torus"), ("tube", "cylinder")):
        with open(out(name, "summary.json")) as f:
            s = json.load(f)
        if (s["chart"] != chart or s["strokes"] < 1 or s["modified_vertices"] <= 0
                or s["touching_frames"] < 20 or s["skipped_frames"] != 0):
            fail(f"the {chart} replay did not sculpt its planet: {s}")
        if chart == "torus" and (s["radius_m"] != 4.5e6 or s["minor_radius_m"] != 1.8e6):
            fail(f"the default torus's dimensions: {s}")
        if chart == "cylinder" and (s["radius_m"] != 6e6 or s["length_m"] != 4e6):
            fail(f"the cylinder's dimensions: {s}")
        for f in ("relief.png", "closeup.png", "view.png", "heightmap.png"):
            if f not in s["files"] or not is_png(out(name, f)):
                fail(f"the {chart} replay did not write {f}: {s['files']}")
        if "renderer" in s and ("ar_view.png" not in s["files"] or "overview.png" not in s["files"]):
            fail(f"the {chart} replay rendered no AR view or overview: {s['files']}")
        meta = json.load(open(out(name, "heightmap.png.json")))
        if meta.get("projection") != chart:
            fail(f"the {chart} replay's heightmap sidecar: {meta}")
        planet = open(out(name, "planet.planet"), "rb").read()
        if not planet[16:32].startswith(chart.encode() + b"\0"):
            fail(f"the {chart} planet file's header: {planet[:32]!r}")
    if open(out("torus_a", "planet.planet"), "rb").read() != open(out("torus_b", "planet.planet"), "rb").read():
        fail("two replays onto the torus wrote different planet files")
    # A road on a tube: --at AROUND,ACROSS (torus, degrees) or AROUND,ALONG (cylinder, degrees and
    # metres), one surface with the road in it, in pieces across the seams (refused until
    # 2026-12-07; before that laid about the torus's centre).
    with open(out("tube_road.obj"), "w") as f:
        f.write("v -5000 -50000 0\nv 5000 -50000 0\nv -5000 50000 0\nv 5000 50000 0\nf 1 2 4\nf 1 4 3\n")
    for name, at, pieces, euler in (("torus_a", "10,10,0", 1, 0), ("torus_a", "0,0,45", 4, 0),
                                    ("tube", "0,100000,90", 2, 0)):
        stdout, _ = run("overlay", out(name, "planet.planet"), out("tube_road.obj"), "--at", at,
                        "--error", "200", "--out", out("tube_road_out.obj"))
        r = json.loads(stdout)
        rims = name == "tube"  # the cylinder's open ends are the mesh's only border
        if (r["euler"] != euler or (r["border_edges"] > 0) != rims or r["non_manifold_edges"] != 0
                or r["road_group_triangles"] < 2 or r["road_pieces"] != pieces or r["road_stray_m"] > 200):
            fail(f"a road at {at} on the {name} planet: {r}")
    _, err = run("overlay", out("tube", "planet.planet"), out("tube_road.obj"), "--at", "0,9000000",
                 "--error", "200", "--out", out("tube_road_off.obj"), expect=2)
    if "metres along it from its middle" not in err or os.path.exists(out("tube_road_off.obj")):
        fail(f"a road off the cylinder's length was not refused by name:\n{err}")
    # Half over the cylinder's rim (10 km from it): clipped there, as at a flat terrain's border
    # (its grid point was clamped onto the rim before, a degenerate road refused).
    stdout, _ = run("overlay", out("tube", "planet.planet"), out("tube_road.obj"), "--at", "30,1990000,0",
                    "--error", "200", "--out", out("tube_road_rim.obj"))
    r = json.loads(stdout)
    if r["euler"] != 0 or r["non_manifold_edges"] != 0 or r["road_triangles_clipped"] < 1 or r["road_group_triangles"] < 2:
        fail(f"a road over the cylinder's rim: {r}")
    # A stroke sculpted on each tube becomes a road (`road` from the replay's log, its place in
    # the tube's own terms) that overlay lays back where it was sculpted; a stroke file's points
    # are a sphere's latitudes and longitudes, refused for a tube by name.
    for name, stroke in (("torus_a", "2"), ("tube", "1")):
        stdout, _ = run("road", out(name, "log.jsonl"), "--planet", out(name, "planet.planet"), "--width", "20000",
                        "--stroke", stroke, "--out", out(f"{name}_stroke_road.obj"))
        road = json.loads(stdout)
        stdout, _ = run("overlay", out(name, "planet.planet"), out(f"{name}_stroke_road.obj"), "--at", road["at"],
                        "--error", "200", "--out", out(f"{name}_stroke_overlay.obj"))
        r = json.loads(stdout)
        if (r["euler"] != 0 or r["non_manifold_edges"] != 0 or r["road_group_triangles"] < road["triangles"]
                or r["road_stray_m"] > 200):
            fail(f"the {name} replay's stroke {stroke} laid as a road: {road}, {r}")
    # A stroke file onto a tube: its points in the planet frame (xyz=), here along the torus's
    # outer equator from the u seam (so the strip's first vertices lie on the seam, where the
    # overlay must weld twins it makes on the other side); LAT LON points are refused by line.
    outer = 4500000 + 1800000
    with open(out("torus_strokes.txt"), "w") as f:
        f.write("stroke xyz=%d,0,0\n" % outer)
        for deg in (0.7, 1.4, 2.1):
            a = math.radians(deg)
            f.write("to xyz=%.3f,%.3f,0\n" % (outer * math.cos(a), outer * math.sin(a)))
        f.write("end\n")
    stdout, _ = run("road", out("torus_strokes.txt"), "--planet", out("torus_a", "planet.planet"),
                    "--width", "20000", "--out", out("torus_file_road.obj"))
    road = json.loads(stdout)
    if road["at"] != "0,0,0" or abs(road["length_m"] - outer * math.radians(2.1)) > 1000:
        fail(f"the torus stroke file's road: {road}")
    stdout, _ = run("overlay", out("torus_a", "planet.planet"), out("torus_file_road.obj"), "--at", road["at"],
                    "--error", "200", "--out", out("torus_file_overlay.obj"))
    r = json.loads(stdout)
    if r["euler"] != 0 or r["border_edges"] != 0 or r["non_manifold_edges"] != 0 or r["road_group_triangles"] < 2:
        fail(f"the torus stroke file's road laid from the seam: {r}")
    _, err = run("road", os.path.join(SRC, "data", "demo-strokes.txt"), "--planet", out("torus_a", "planet.planet"),
                 "--width", "5000", "--out", out("torus_latlon_road.obj"), expect=2)
    if ("demo-strokes.txt:7: a LAT LON point needs a sphere" not in err
            or os.path.exists(out("torus_latlon_road.obj"))):
        fail(f"a stroke file of LAT LON points onto the torus was not refused by line:\n{err}")
    # The sand core on the tubes: the displacement tool with settling along the same frames, twice
    # onto the torus (the same planet file and forces), once onto the cylinder; the haptic force
    # path beside them writes forces.csv.
    for name, args in (("torus_sand_a", ("--chart", "torus")), ("torus_sand_b", ("--chart", "torus")),
                       ("tube_sand", ("--chart", "cylinder", "--radius", "6000000", "--length", "4000000"))):
        run("replay", video, "--calib", CALIB, *args, "--tool", "displace", "--grid", "513",
            "--max-frames", "230", "--out", out(name))
    for name in ("torus_sand_a", "tube_sand"):
        with open(out(name, "summary.json")) as f:
            s = json.load(f)
        if s["stamps"] < 1 or s["modified_vertices"] <= 0 or "forces.csv" not in s["files"]:
            fail(f"the sand replay {name} did not displace sand or wrote no forces: {s}")
    for f in ("planet.planet", "forces.csv"):
        if open(out("torus_sand_a", f), "rb").read() != open(out("torus_sand_b", f), "rb").read():
            fail(f"two displacement replays onto the torus wrote different {f}")
    # The TIN sand tool on both tubes (issue 43), its region TIN across the seams where the strokes
    # cross them; on the default torus its stamp must be small enough for the tube's tangent plane
    # (a region of 2.5 radii within a quarter of the tube radius, 1,800 km: at most 180 km).
    for name, args in (("torus_tin", ("--chart", "torus")),
                       ("tube_tin", ("--chart", "cylinder", "--radius", "6000000", "--length", "4000000"))):
        run("replay", video, "--calib", CALIB, *args, "--tool", "tin-sand", "--displace-radius-km", "150",
            "--grid", "1025", "--max-frames", "230", "--out", out(name))
        with open(out(name, "summary.json")) as f:
            s = json.load(f)
        if s["tool"] != "tin-sand" or s["stamps"] < 1 or s["modified_vertices"] <= 0:
            fail(f"the TIN sand replay {name} did not sculpt: {s}")
    p = subprocess.run([EXE, "replay", video, "--calib", CALIB, "--chart", "torus", "--grid", "1025",
                        "--max-frames", "5", "--tool", "tin-sand", "--out", out("refused_tin")],
                       capture_output=True, text=True)
    if p.returncode <= 0 or "too curved" not in p.stderr:
        fail(f"a 400 km TIN sand stamp on the default torus was not refused as too curved: {p.stderr}")
    # The sculpted torus's heightmap goes back onto a torus of the same dimensions, and its mesh
    # export is a closed surface of Euler characteristic 0.
    run("import", out("torus_a", "heightmap.png"), "--chart", "torus", "--radius", "4500000",
        "--minor-radius", "1800000", "--out", out("torus_back.planet"))
    # Impossible or misplaced dimensions, refused naming the option; nothing replayed.
    for args, said in ((("--chart", "torus", "--radius", "1500000"), "--minor-radius 1800000 m must be below --radius 1500000 m"),
                       (("--chart", "torus", "--minor-radius", "5e6", "--radius", "5e6"), "--minor-radius"),
                       (("--chart", "cylinder", "--length", "-1"), "--length -1 m"),
                       (("--chart", "cylinder", "--radius", "0"), "--radius 0 m"),
                       (("--chart", "latlong", "--length", "5"), "--length is a cylinder's"),
                       (("--chart", "torus", "--length", "5"), "--length is a cylinder's"),
                       (("--chart", "cylinder", "--minor-radius", "5"), "--minor-radius is a torus's"),
                       (("--radius", "5e6", "--planet", out("torus_a", "planet.planet")), "has its own dimensions")):
        p = subprocess.run([EXE, "replay", video, "--calib", CALIB, "--grid", "129", "--max-frames", "5", *args,
                            "--out", out("refused")], capture_output=True, text=True)
        if p.returncode <= 0 or said not in p.stderr:
            fail(f"replay {' '.join(args)} was not refused saying '{said}': {p.returncode} {p.stderr}")
    if os.path.exists(out("refused")):
        fail("a refused replay wrote its output folder")
