#!/usr/bin/env python3
"""ctest cli_*: each `planetsculpt` command end to end on small inputs, its outputs checked.

Usage: cli_commands.py GROUP EXE SOURCE_DIR OUT_DIR [BENCH]
Groups: demo, import_export, road, synth_detect, markers, bench (with a benchmark's name), errors, openmp. (`live` has live_smoke.sh;
`calibrate` runs from ps_tests, TrackingCalibrate.CommandCalibratesAFolderOfRenderedViews,
which renders the views it reads.) Python's standard library only: the values are compared
through the raw float32 format, which needs no image decoder.
"""
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import time

GROUP, EXE, SRC, OUT = sys.argv[1:5]
CALIB = os.path.join(SRC, "calib", "synthetic-640x480.yml")


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def run(*args, expect=0):
    """Runs the command; returns (stdout, stderr). A signal (a crash) always fails."""
    env = dict(os.environ)
    if args and (args[0] == "demo" or "--render" in args or "--pictures" in args):
        # Under the asan preset: Mesa's llvmpipe leaves allocations in a module it has unloaded
        # by exit, which no suppression can name (240 bytes, docs/CI.md); any run that renders
        # (the demo, a replay's pictures) is checked without leak detection; the unit tests
        # check the renderer's leaks.
        env["ASAN_OPTIONS"] = env.get("ASAN_OPTIONS", "") + ":detect_leaks=0"
    p = subprocess.run([EXE, *args], capture_output=True, text=True, env=env)
    if p.returncode < 0:
        fail(f"{' '.join(args)}: killed by signal {-p.returncode}\n{p.stderr[-3000:]}")
    if expect is not None and p.returncode != expect:
        fail(f"{' '.join(args)}: exit {p.returncode}, expected {expect}\n{p.stderr[-3000:]}")
    return p.stdout, p.stderr


def out(*parts):
    return os.path.join(OUT, *parts)


def write_raw(path, width, height, values, extra=None):
    with open(path, "wb") as f:
        f.write(struct.pack(f"<{len(values)}f", *values))
    meta = {"format": "float32le", "width": width, "height": height}
    meta.update(extra or {})
    with open(path + ".json", "w") as f:
        json.dump(meta, f)


def read_raw(path):
    with open(path + ".json") as f:
        meta = json.load(f)
    with open(path, "rb") as f:
        data = f.read()
    n = meta["width"] * meta["height"]
    if len(data) != 4 * n:
        fail(f"{path}: {len(data)} bytes for {meta['width']}x{meta['height']} float32")
    return meta, struct.unpack(f"<{n}f", data)


def gdalinfo(path):
    p = subprocess.run(["gdalinfo", "-json", path], capture_output=True, text=True)
    if p.returncode != 0:
        fail(f"gdalinfo could not read {path} (apt install gdal-bin):\n{p.stderr}")
    return json.loads(p.stdout)


def write_pds3(label, image):
    """A 64x32 simple-cylindrical PDS3 product of the Moon: radii = value * 0.5 + 1737400 m."""
    w, h = 64, 32
    vals = [int(1000 * math.sin(x / 10.0) + 200 * y) for y in range(h) for x in range(w)]
    with open(image, "wb") as f:
        f.write(struct.pack(f">{len(vals)}h", *vals))
    lines = ["PDS_VERSION_ID = PDS3", "RECORD_TYPE = FIXED_LENGTH", f"RECORD_BYTES = {2 * w}",
             f"FILE_RECORDS = {h}", f'^IMAGE = "{os.path.basename(image)}"', "OBJECT = IMAGE",
             f"  LINES = {h}", f"  LINE_SAMPLES = {w}", "  SAMPLE_TYPE = MSB_INTEGER",
             "  SAMPLE_BITS = 16", "  SCALING_FACTOR = 0.5", "  OFFSET = 1737400", "END_OBJECT = IMAGE",
             "OBJECT = IMAGE_MAP_PROJECTION", '  MAP_PROJECTION_TYPE = "SIMPLE CYLINDRICAL"',
             "  A_AXIS_RADIUS = 1737.4 <KM>", "  B_AXIS_RADIUS = 1737.4 <KM>",
             "  C_AXIS_RADIUS = 1737.4 <KM>", '  POSITIVE_LONGITUDE_DIRECTION = "EAST"',
             "  CENTER_LATITUDE = 0.0 <DEG>", "  CENTER_LONGITUDE = 180.0 <DEG>",
             f"  MAP_RESOLUTION = {w / 360.0} <PIX/DEG>",
             f"  MAP_SCALE = {2 * math.pi * 1737.4 / w} <KM/PIXEL>",
             "  MAXIMUM_LATITUDE = 90.0 <DEG>", "  MINIMUM_LATITUDE = -90.0 <DEG>",
             f"  LINE_PROJECTION_OFFSET = {h / 2 - 0.5} <PIXEL>",
             f"  SAMPLE_PROJECTION_OFFSET = {w / 2 - 0.5} <PIXEL>",
             "  EASTERNMOST_LONGITUDE = 360.0 <DEG>", "  WESTERNMOST_LONGITUDE = 0.0 <DEG>",
             '  COORDINATE_SYSTEM_NAME = "PLANETOCENTRIC"', "END_OBJECT = IMAGE_MAP_PROJECTION", "END"]
    with open(label, "w") as f:
        f.write("\n".join(lines) + "\n")


def is_png(path):
    with open(path, "rb") as f:
        return f.read(8) == b"\x89PNG\r\n\x1a\n"


def group_demo():
    # The first 60 frames of the bundled demo (the demo's story on the planet board, the
    # default markers), replayed by `demo` on a small planet: every file it announces is
    # written, the pictures are PNGs, the recording sculpted the planet, and the summary
    # compares the replay with the ground truth beside the video (data/demo.truth.jsonl).
    # The recording has no session sidecar: the demo sculpts the default planet, octahedral.
    run("demo", "--max-frames", "60", "--grid", "1025", "--out", out("demo"))
    with open(out("demo", "summary.json")) as f:
        s = json.load(f)
    if s["frames"] != 60:
        fail(f"demo replayed {s['frames']} frames of 60")
    if s["chart"] != "octahedral":
        fail(f"the demo's planet is {s['chart']}, not the default chart (octahedral)")
    # The close-up frames the largest change (its latitude and longitude in the equirectangular
    # picture), in a small part of the picture.
    box, (pw, ph) = s["closeup_box_px"], s["picture_px"]
    lat, lon = s["largest_change_lat_lon_deg"]
    px, py = (lon + 180) / 360 * pw, (90 - lat) / 180 * ph
    if not (box[0] - 1 <= px <= box[0] + box[2] + 1 and box[1] - 1 <= py <= box[1] + box[3] + 1) \
            or box[2] * box[3] > 0.1 * pw * ph:
        fail(f"the demo's close-up box {box} of {pw}x{ph} does not frame its largest change at ({px:.0f}, {py:.0f})")
    if s["planet_tracked"] + s["planet_held"] != s["frames_with_planet"] or s["planet_lost"] != 60 - s["frames_with_planet"]:
        fail(f"the planet's tracked / held / lost counts do not add up: {s}")
    t = s.get("truth")
    if not t or t["frames"] != 60 or t["touching_frames"] < 20:
        fail(f"no comparison with the ground truth in the summary: {t}")
    if t["sculpted_when_touching"] < 0.95 * t["touching_frames"] or t["pose_when_in_view"] != t["planet_in_view"]:
        fail(f"the board demo lost the planet or missed touching frames: {t}")
    if not (0 <= t["tip_error_mm"]["median"] < 2 and t["planet_centre_error_mm"]["median"] < 1):
        fail(f"tip or planet centre far from the truth: {t}")
    if not (0 < s["largest_change_m"] < 1e5) or s["modified_vertices"] <= 0 or s["strokes"] < 1:
        fail("the replay did not change the planet's heights within reason")
    for name in s["files"]:
        p = out("demo", name)
        if not os.path.getsize(p):
            fail(f"demo announced {name} but wrote nothing")
        if name.endswith(".png") and not is_png(p):
            fail(f"{p} is not a PNG")
    leftovers = [n for n in os.listdir(out("demo")) if n.endswith(".part")]
    if leftovers:
        fail(f"temporary files left: {leftovers}")
    frames = [json.loads(l) for l in open(out("demo", "log.jsonl"))]
    if len([l for l in frames if "frame" in l]) < 60:
        fail("log.jsonl holds fewer lines than frames")
    # A stroke sculpted in the recording becomes a road (a strip mesh) that overlay takes.
    stdout, _ = run("road", out("demo", "log.jsonl"), "--planet", out("demo", "planet.planet"),
                    "--width", "100000", "--out", out("demo", "stroke_road.obj"))
    road = json.loads(stdout)
    if road["points"] < 2 or road["triangles"] != 2 * (road["points"] - 1):
        fail(f"road from the demo's log: {road}")
    stdout, _ = run("overlay", out("demo", "planet.planet"), out("demo", "stroke_road.obj"), "--at", road["at"],
                    "--mode", "stencil", "--error", "500", "--out", out("demo", "stroke_road_stencil.glb"))
    r = json.loads(stdout)
    if r["euler"] != 2 or r["border_edges"] != 0 or r["footprint_error_m"] > 1e-3:
        fail(f"the demo's stroke stenciled into its planet: {r}")
    # The sand TIN tool: the AR view draws its region TIN spliced into the 4-8 mesh, and a
    # replay writes the same pictures twice, bit for bit (issue 27). On lat-long: the tool is
    # refused on the octahedral chart today (group_charts).
    tin_pictures = []
    for k in (1, 2):
        run("replay", os.path.join(SRC, "data", "demo.mkv"), "--calib", CALIB, "--grid", "513", "--chart", "latlong",
            "--max-frames", "45", "--tool", "tin-sand", "--pictures", "--render", "--render-every", "15",
            "--out", out(f"tin{k}"))
        with open(out(f"tin{k}", "summary.json")) as f:
            s = json.load(f)
        if s.get("ar_stroke_tin_frames", 0) < 1 or s["stamps"] < 1:
            fail(f"replay --tool tin-sand drew no frame with its region TIN: {s}")
        names = sorted(os.listdir(out(f"tin{k}", "ar"))) + ["ar_view.png", "overview.png"]
        # The force path feels the region TIN where the tool is in it (docs/HAPTICS.md).
        names.append("forces.csv")
        tin_pictures.append({n: open(out(f"tin{k}", "ar", n) if n in os.listdir(out(f"tin{k}", "ar"))
                                     else out(f"tin{k}", n), "rb").read() for n in names})
    if tin_pictures[0] != tin_pictures[1]:
        differ = [n for n in tin_pictures[0] if tin_pictures[0][n] != tin_pictures[1].get(n)]
        fail(f"two replays with --tool tin-sand wrote different pictures or forces: {differ}")
    # A recording made with the single planet and tool markers: the default board and cube
    # see nothing and say how to replay it; with --board single --tool-layout flat it sculpts.
    video = out("short.mkv")
    run("synth", "short", "--out", video)
    run("replay", video, "--calib", CALIB, "--grid", "1025", "--out", out("short-board"))
    with open(out("short-board", "summary.json")) as f:
        s = json.load(f)
    if s["frames_with_planet"] != 0 or not any("--board single --tool-layout flat" in w for w in s["warnings"]):
        fail(f"a single-marker recording under the default board: {s['warnings']}")
    run("replay", video, "--calib", CALIB, "--grid", "1025", "--board", "single", "--tool-layout", "flat",
        "--out", out("short"))
    with open(out("short", "summary.json")) as f:
        s = json.load(f)
    if s["frames_with_planet"] < 10 or s["touching_frames"] < 1 or s["strokes"] < 1:
        fail(f"the single-marker recording tracked or sculpted too little: {s}")


def group_import_export():
    # A flat tile through raw float32: import then export at its own size gives the same floats
    # back, bit for bit (the grid is the tile's own 2^n+1 side).
    w = h = 33
    tile = [100.0 * math.sin(0.3 * x) * math.cos(0.2 * y) + 0.25 * x for y in range(h) for x in range(w)]
    tile = list(struct.unpack(f"<{len(tile)}f", struct.pack(f"<{len(tile)}f", *tile)))  # float32
    write_raw(out("tile.raw"), w, h, tile)
    run("import", out("tile.raw"), "--chart", "flat", "--spacing", "30", "--out", out("tile.planet"))
    run("export", out("tile.planet"), "--out", out("tile_back.raw"))
    meta, back = read_raw(out("tile_back.raw"))
    if (meta["width"], meta["height"]) != (w, h):
        fail(f"flat round trip came back {meta['width']}x{meta['height']}, not {w}x{h}")
    worst = max(abs(a - b) for a, b in zip(tile, back))
    if worst != 0.0:
        fail(f"flat round trip changed heights by up to {worst} m")
    # A global lat-long field (smooth: one bilinear resampling each way) comes back close.
    w, h = 128, 64
    field = []
    for y in range(h):
        lat = math.pi / 2 - (y + 0.5) * math.pi / h
        for x in range(w):
            lon = -math.pi + (x + 0.5) * 2 * math.pi / w
            field.append(2000.0 * math.cos(lat) * math.sin(2 * lon) + 500.0 * math.sin(lat))
    write_raw(out("globe.raw"), w, h, field)
    run("import", out("globe.raw"), "--chart", "latlong", "--grid", "257", "--radius", "1737400",
        "--out", out("globe.planet"))
    run("export", out("globe.planet"), "--width", str(w), "--height", str(h), "--out", out("globe_back.raw"))
    _, back = read_raw(out("globe_back.raw"))
    rms = math.sqrt(sum((a - b) ** 2 for a, b in zip(field, back)) / len(field))
    if not rms < 20.0:  # 0.5 % of the field's 4 km range
        fail(f"lat-long round trip rms {rms:.2f} m (over 20 m)")
    # The same globe onto the octahedral chart: a version 2 planet file that names its chart,
    # and the export reads it back through the chart's inverse.
    said, _ = run("import", out("globe.raw"), "--chart", "octahedral", "--grid", "257", "--radius", "1737400",
                  "--out", out("globe_octa.planet"))
    if "octahedral planet" not in said:
        fail(f"import --chart octahedral did not say it made an octahedral planet:\n{said}")
    with open(out("globe_octa.planet"), "rb") as f:
        head = f.read(32)
    if struct.unpack("<I", head[8:12])[0] != 2 or not head[16:32].startswith(b"octahedral\0"):
        fail(f"the octahedral planet file's header is {head!r}")
    run("export", out("globe_octa.planet"), "--width", str(w), "--height", str(h), "--out", out("octa_back.raw"))
    _, back = read_raw(out("octa_back.raw"))
    rms = math.sqrt(sum((a - b) ** 2 for a, b in zip(field, back)) / len(field))
    if not rms < 20.0:
        fail(f"octahedral round trip rms {rms:.2f} m (over 20 m)")
    # Without --chart an equirectangular image becomes an octahedral planet, the same file.
    said, _ = run("import", out("globe.raw"), "--grid", "257", "--radius", "1737400",
                  "--out", out("globe_default.planet"))
    if "octahedral planet" not in said:
        fail(f"import without --chart did not make an octahedral planet (the default):\n{said}")
    if open(out("globe_default.planet"), "rb").read() != open(out("globe_octa.planet"), "rb").read():
        fail("import without --chart wrote another file than import --chart octahedral")
    # GeoTIFFs that GIS tools read with the right CRS (gdalinfo, GDAL's own reader).
    run("export", out("globe.planet"), "--width", str(w), "--height", str(h), "--out", out("globe.tif"))
    info = gdalinfo(out("globe.tif"))
    if info["size"] != [w, h] or info["geoTransform"] != [-180.0, 360.0 / w, 0.0, 90.0, 0.0, -180.0 / h]:
        fail(f"globe.tif: size {info['size']}, geotransform {info['geoTransform']}")
    wkt = info["coordinateSystem"]["wkt"]
    if not wkt.startswith("GEOGCRS") or "ELLIPSOID[" not in wkt or ",1737400,0," not in wkt:
        fail(f"globe.tif is not on a geographic CRS of a 1737.4 km sphere:\n{wkt}")
    run("export", out("tile.planet"), "--out", out("tile.tif"))
    info = gdalinfo(out("tile.tif"))
    if info["geoTransform"][1] != 30.0 or info["geoTransform"][5] != -30.0:
        fail(f"tile.tif: pixel size {info['geoTransform']}, not 30 m")
    if info.get("metadata", {}).get("", {}).get("AREA_OR_POINT") != "Point":
        fail("tile.tif is not pixel-is-point")
    # A PDS3 product (label + image, how NASA ships LOLA and MOLA grids): its label's sphere,
    # scale, offset (distances from the centre) and projection are used.
    write_pds3(out("moon.lbl"), out("moon.img"))
    _, err = run("import", out("moon.lbl"), "--grid", "129", "--out", out("moon.planet"))
    for said in ("radius 1737400 m, from the file", "the radius 1737400 m is subtracted",
                 "column 0 starts at 0 deg longitude"):
        if said not in err:
            fail(f"PDS3 import did not say '{said}':\n{err}")
    run("export", out("moon.planet"), "--out", out("moon.raw"), "--width", "64", "--height", "32")
    meta, back = read_raw(out("moon.raw"))
    if meta.get("radius_m") != 1737400.0 or not (-560 < min(back) and max(back) < 3660):
        fail(f"PDS3 planet: radius {meta.get('radius_m')}, heights {min(back)} .. {max(back)}")
    # An SRTM .hgt tile (big-endian int16, named by its corner) through GDAL's SRTMHGT driver.
    side = 1201
    hgt = [int(100 * math.sin(x / 50.0) + y) for y in range(side) for x in range(side)]
    with open(out("N46W122.hgt"), "wb") as f:
        f.write(struct.pack(f">{len(hgt)}h", *hgt))
    _, err = run("import", out("N46W122.hgt"), "--chart", "flat", "--grid", "129", "--out", out("hgt.planet"))
    if "georeferencing in degrees, at latitude 46.5" not in err:
        fail(f"the .hgt tile was not read as a geographic SRTM tile:\n{err}")
    # A globe's equirectangular image does not go onto a torus: refused by name, nothing written.
    p = subprocess.run([EXE, "import", out("octa_back.raw"), "--chart", "torus", "--radius", "3000",
                        "--minor-radius", "1000", "--out", out("torus.planet")], capture_output=True, text=True)
    if p.returncode <= 0 or "octa_back.raw" not in p.stderr or "equirectangular" not in p.stderr:
        fail(f"an equirectangular image onto a torus was not refused by name: {p.returncode} {p.stderr}")
    if os.path.exists(out("torus.planet")):
        fail("a refused import still wrote its planet file")
    # A torus from an image of its (u, v) grid (64 x 64, both ways periodic): the dimensions from
    # the command line; exported at its grid's size, the same image comes back, value for value.
    tube = [60.0 * math.sin(2 * math.pi * x / 64) * math.cos(2 * math.pi * y / 64) for y in range(64) for x in range(64)]
    write_raw(out("tube.raw"), 64, 64, tube)
    p = subprocess.run([EXE, "import", out("tube.raw"), "--chart", "torus", "--radius", "3000",
                        "--out", out("torus.planet")], capture_output=True, text=True)
    if p.returncode <= 0 or "tube.raw" not in p.stderr or "--minor-radius" not in p.stderr:
        fail(f"a torus without its tube's radius was not refused by name: {p.returncode} {p.stderr}")
    run("import", out("tube.raw"), "--chart", "torus", "--radius", "3000", "--minor-radius", "1000",
        "--out", out("torus.planet"))
    run("export", out("torus.planet"), "--out", out("torus_back.raw"))
    meta, back = read_raw(out("torus_back.raw"))
    if (meta.get("projection") != "torus" or meta.get("minor_radius_m") != 1000.0 or
            [meta["width"], meta["height"]] != [64, 64]):
        fail(f"the torus's heightmap sidecar is {meta}")
    stored = struct.unpack(f"<{len(tube)}f", struct.pack(f"<{len(tube)}f", *tube))
    if max(abs(a - b) for a, b in zip(stored, back)) != 0.0:
        fail("the torus's heightmap did not come back value for value")
    # A regional tile cannot be stretched round a sphere: refused by name on either sphere chart.
    for chart in ("latlong", "octahedral"):
        p = subprocess.run([EXE, "import", out("N46W122.hgt"), "--chart", chart, "--out", out("hgt_globe.planet")],
                           capture_output=True, text=True)
        if p.returncode <= 0 or "N46W122.hgt" not in p.stderr or "--chart flat" not in p.stderr:
            fail(f"a 1-degree tile onto the {chart} chart was not refused by name: {p.returncode} {p.stderr}")
    if os.path.exists(out("hgt_globe.planet")):
        fail("a refused import still wrote its planet file")
    # Meshes: OBJ vertices lie within the requested error of the surface's height range; PLY
    # and GLB carry their magic bytes.
    run("export", out("tile.planet"), "--max-error", "1", "--out", out("tile.obj"))
    verts = [tuple(map(float, l.split()[1:4])) for l in open(out("tile.obj")) if l.startswith("v ")]
    faces = [l for l in open(out("tile.obj")) if l.startswith("f ")]
    if len(verts) < 4 or len(faces) < 2:
        fail(f"tile.obj has {len(verts)} vertices, {len(faces)} faces")
    lo, hi = min(tile), max(tile)
    for v in verts:
        if not (lo - 1e-3 <= v[2] <= hi + 1e-3) or not all(map(math.isfinite, v)):
            fail(f"OBJ vertex {v} outside the tile's heights [{lo}, {hi}]")
    run("export", out("tile.planet"), "--max-error", "1", "--out", out("tile.ply"))
    run("export", out("globe.planet"), "--max-error", "50", "--out", out("globe.glb"))
    if not open(out("tile.ply"), "rb").read(4) == b"ply\n":
        fail("tile.ply has no PLY header")
    if not open(out("globe.glb"), "rb").read(4) == b"glTF":
        fail("globe.glb has no glTF magic")
    # TINs: the error measured on every sample of the file as written; a road stitched and
    # stenciled into the tile (its x, y the tile's metres); a demo stroke as a road on the globe.
    stdout, _ = run("export", out("tile.planet"), "--tin", "--max-error", "1", "--out", out("tile_tin.obj"))
    tin = json.loads(stdout)
    if not (tin["tin"] and tin["measured_error_ratio"] <= 1.0 and tin["samples_checked"] == 33 * 33):
        fail(f"export --tin: {tin}")
    with open(out("road.obj"), "w") as f:
        f.write("v 100 200 0\nv 850 500 0\nv 850 560 0\nv 100 260 0\nf 1 2 3\nf 1 3 4\n")
    for mode in ("stitch", "stencil"):
        stdout, _ = run("overlay", out("tile.planet"), out("road.obj"), "--mode", mode, "--error", "1",
                        "--out", out(f"road_{mode}.obj"))
        r = json.loads(stdout)
        if r["euler"] != 1 or r["non_manifold_edges"] != 0 or r["road_group_triangles"] < 2:
            fail(f"overlay --mode {mode}: {r}")
        if mode == "stitch" and not (r["crossing_vertices"] > 0 and r["added_vertex_error_m"] < 1e-6):
            fail(f"overlay --mode stitch: {r}")
        if mode == "stencil" and not (r["footprint_error_m"] < 1e-6 and r["outside_error_ratio"] <= 1 + 1e-9):
            fail(f"overlay --mode stencil: {r}")
        if "g road" not in open(out(f"road_{mode}.obj")).read():
            fail(f"road_{mode}.obj has no road group")
    # The terrain as a mesh this project wrote (the tile's TIN): stitched, every vertex kept.
    for mode in ("stitch", "stencil"):
        stdout, _ = run("overlay", out("tile_tin.obj"), out("road.obj"), "--mode", mode, "--error", "1",
                        "--out", out(f"mesh_road_{mode}.obj"))
        r = json.loads(stdout)
        if r["euler"] != 1 or r["non_manifold_edges"] != 0 or r.get("outside_error_ratio", 0) > 1 + 1e-9:
            fail(f"overlay onto a TIN mesh, --mode {mode}: {r}")
        if mode == "stitch" and r["terrain_tin_vertices"] != tin["vertices"]:
            fail(f"overlay onto a TIN mesh re-meshed it: {r['terrain_tin_vertices']} vertices, not {tin['vertices']}")
    run("export", out("globe.planet"), "--tin", "--max-error", "500", "--out", out("globe_tin.obj"))
    _, err = run("overlay", out("globe_tin.obj"), out("road.obj"), "--error", "1", "--out", out("x.obj"), expect=2)
    if "not a heightfield" not in err:
        fail(f"a sphere's mesh as the terrain was not refused as such:\n{err}")
    stdout, _ = run("road", os.path.join(SRC, "data", "demo-strokes.txt"), "--width", "20000",
                    "--planet", out("globe.planet"), "--out", out("demo_road.obj"))
    road = json.loads(stdout)
    stdout, _ = run("overlay", out("globe.planet"), out("demo_road.obj"), "--at", road["at"],
                    "--mode", "stitch", "--error", "200", "--out", out("globe_road.ply"))
    r = json.loads(stdout)
    if r["euler"] != 2 or r["border_edges"] != 0 or r["road_group_triangles"] < road["triangles"]:
        fail(f"a demo stroke overlaid on the globe: {r}")
    # Roads across the glued sides of a planet's grid (an octahedral fold, a southern half-meridian
    # at 0, 90, 180 or -90 degrees; the south pole, the grid's four corners; lat-long's seam): cut
    # where they cross, laid in pieces that meet twin to twin, one closed mesh; every vertex of the
    # road group within 1 % of the road's width of its footprint on the sphere. (An octahedral
    # road along a fold was mirrored into a wrong road before 2026-12-07, and one across it refused
    # as "crossing itself".) Around the end of a fold (the equator at those longitudes, where
    # the grid turns half round) a road is laid in two halves that meet across the fold (refused
    # by name before 2026-12-07).
    run("import", out("globe.raw"), "--chart", "octahedral", "--grid", "257", "--radius", "1737400",
        "--out", out("globe_octa.planet"))
    with open(out("strip.obj"), "w") as f:  # 200 km x 10 km, along its +y axis
        for i in range(9):
            y = -100e3 + 25e3 * i
            f.write(f"v -5000 {y} 0\nv 5000 {y} 0\n")
        for i in range(8):
            a = 2 * i + 1
            f.write(f"f {a} {a + 1} {a + 3}\nf {a} {a + 3} {a + 2}\n")

    def off_footprint(mesh, lat, lon, heading, radius):
        # The largest distance (m) of a road-group vertex outside the strip, in the strip's
        # tangent plane (the gnomonic projection the road was placed by).
        vs, road_faces, group = [], [], None
        for line in open(mesh):
            if line.startswith("v "):
                vs.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("g "):
                group = line.split()[1]
            elif line.startswith("f ") and group == "road":
                road_faces.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
        la, lo, h = (math.radians(a) for a in (lat, lon, heading))
        up = (math.cos(la) * math.cos(lo), math.cos(la) * math.sin(lo), math.sin(la))
        east = (-math.sin(lo), math.cos(lo), 0.0)
        north = (up[1] * east[2] - up[2] * east[1], up[2] * east[0] - up[0] * east[2], up[0] * east[1] - up[1] * east[0])
        xa = [east[i] * math.cos(h) - north[i] * math.sin(h) for i in range(3)]
        ya = [north[i] * math.cos(h) + east[i] * math.sin(h) for i in range(3)]
        worst = 0.0
        for face in road_faces:
            for k in face:
                t = sum(vs[k][i] * up[i] for i in range(3))
                x = sum(vs[k][i] * xa[i] for i in range(3)) / t * radius
                y = sum(vs[k][i] * ya[i] for i in range(3)) / t * radius
                worst = max(worst, abs(x) - 5000, abs(y) - 100e3)
        return worst, len(road_faces)

    # Near the poles the chart bends a straight grid edge: the road's edges are halved until they
    # stray at most --error (200 m) from its path (25 km edges 2 degrees from the octahedral
    # south pole strayed 2.1 km before 2026-12-07). Stitched, the road is draped over the terrain's
    # mesh, its vertices on the normals through their own points and its edges in their own planes
    # (before, put on the mesh's flat 24 km triangles at their grid points, they slid up to 210 m
    # at 75 degrees N on lat-long, 176 m at the octahedral south pole): within 1 m of its footprint
    # where it is laid whole, within 50 m where it is cut at a glued side (its vertices on the
    # side stay there, at their twins' places).
    for planet, at, crosses in (("globe_octa", (-45, 0, 0), True), ("globe_octa", (-45, 0, 90), True),
                                ("globe_octa", (-30, -90, 35), True), ("globe", (10, 180, 90), True),
                                ("globe_octa", (-88, 30, 0), True), ("globe_octa", (89, 0, 0), False),
                                ("globe", (75, 20, 60), False), ("globe_octa", (0, -90, 0), True)):
        bound = 50 if crosses else 1
        where = ",".join(str(a) for a in at)
        stdout, _ = run("overlay", out(f"{planet}.planet"), out("strip.obj"), "--at", where, "--error", "200",
                        "--out", out("folded_road.obj"))
        r = json.loads(stdout)
        worst, faces = off_footprint(out("folded_road.obj"), *at, 1737400)
        if (r["euler"] != 2 or r["border_edges"] != 0 or r["non_manifold_edges"] != 0 or faces < 16
                or worst > bound or (r["road_pieces"] > 1) != crosses or r["road_stray_m"] > 200
                or r["road_undraped_edges"] != 0):
            fail(f"a road at {where} on {planet}: {r}, {faces} road triangles, {worst:.0f} m off its footprint")


def group_road():
    # `road` makes a strip mesh from a stroke; `track`, its old name, does the same and says on
    # stderr, in one line naming `road`, that it is deprecated.
    strokes = os.path.join(SRC, "data", "demo-strokes.txt")
    new_out, new_err = run("road", strokes, "--width", "5000", "--stroke", "2", "--out", out("road.obj"))
    old_out, old_err = run("track", strokes, "--width", "5000", "--stroke", "2", "--out", out("track.obj"))
    if "deprecated" in new_err:
        fail(f"road called itself deprecated: {new_err}")
    lines = old_err.strip().splitlines()
    if len(lines) != 1 or "deprecated" not in lines[0] or "road" not in lines[0]:
        fail(f"track did not say, in one line naming road, that it is deprecated: {old_err!r}")
    new, old = json.loads(new_out), json.loads(old_out)
    if new["file"] != out("road.obj") or old["file"] != out("track.obj"):
        fail(f"the summaries name other files: {new['file']}, {old['file']}")
    del new["file"], old["file"]
    if new != old or new["stroke"] != 2 or new["triangles"] != 2 * (new["points"] - 1):
        fail(f"track and road differ or made no strip: {old} vs {new}")
    if open(out("road.obj"), "rb").read() != open(out("track.obj"), "rb").read():
        fail("track wrote another mesh than road")
    if "PlanetSculpt road: stroke 2" not in open(out("road.obj")).read():
        fail("road.obj does not say what it is")


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
    _, err = run("road", os.path.join(SRC, "data", "demo-strokes.txt"), "--planet", out("torus_a", "planet.planet"),
                 "--width", "5000", "--out", out("torus_file_road.obj"), expect=2)
    if "a stroke file's points are latitudes and longitudes" not in err or os.path.exists(out("torus_file_road.obj")):
        fail(f"a stroke file's road onto the torus was not refused by name:\n{err}")
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


def group_synth_detect():
    # A rendered still scene: `detect` finds the tool marker where the ground truth put it.
    video = out("still.mkv")
    run("synth", "still", "--frames", "3", "--out", video)
    truth = [json.loads(l) for l in open(out("still.truth.jsonl"))]
    frames = {t["frame"]: t for t in truth if t.get("type") == "frame"}
    stdout, _ = run("detect", video, "--calib", CALIB, "--marker-size", "0.05", "--ids", "1")
    found = [json.loads(l) for l in stdout.splitlines() if l.startswith("{")]
    if len(found) != 3:
        fail(f"detect found the tool marker in {len(found)} of 3 frames")
    for d in found:
        if d["id"] != 1 or len(d["corners"]) != 4:
            fail(f"unexpected detection {d}")
        t = frames[d["frame"]]["tool"]["tvec"]
        err = math.dist(d["tvec"], t)
        if err > 0.002:
            fail(f"frame {d['frame']}: tool marker at {d['tvec']}, truth {t} ({err * 1000:.2f} mm)")


    # A still image is searched at full size (decimate 1), a video as the live path does.
    _, err = run("detect", os.path.join(SRC, "docs", "images", "ar_view.png"))
    if " d1 " not in err:
        fail(f"detect on a still image did not search at decimate 1: {err}")
    _, err = run("detect", os.path.join(SRC, "docs", "images", "ar_view.png"), "--decimate", "2")
    if " d2 " not in err:
        fail(f"detect --decimate 2 on a still image was not searched at decimate 2: {err}")
    _, err = run("detect", video, "--max-frames", "1", "--ids", "1")
    if " d2 " not in err:
        fail(f"detect on a video did not keep decimate 2: {err}")


def group_markers():
    # The sheets: PNGs that `detect` reads back with every id, PDFs of the paper's size.
    run("markers", "--out", out("sheets"), "--paper", "a4")
    expected = {"planet-marker-a4": {0}, "tool-marker-a4": {1},
                "planet-board-a4": set(range(10, 19)), "tool-cube-a4": set(range(20, 25))}
    for name, ids in expected.items():
        png, pdf = out("sheets", name + ".png"), out("sheets", name + ".pdf")
        if not is_png(png):
            fail(f"{png} is not a PNG")
        data = open(pdf, "rb").read()
        if not data.startswith(b"%PDF-") or b"595.2" not in data:
            fail(f"{pdf} is not an A4 PDF")
        stdout, _ = run("detect", png, "--decimate", "1")
        seen = {json.loads(l)["id"] for l in stdout.splitlines() if l.startswith("{")}
        if not ids <= seen:
            fail(f"{png}: detect read ids {sorted(seen)}, the sheet holds {sorted(ids)}")


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
    name = sys.argv[5] if len(sys.argv) > 5 else ""
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


def group_errors():
    # Bad input: a clear error naming the file, a non-zero exit, never a crash.
    missing = out("no-such-file.planet")
    _, err = run("export", missing, "--out", out("x.png"), expect=None)
    if missing not in err:
        fail(f"export of a missing file did not name it: {err}")
    with open(out("bad.planet"), "wb") as f:
        f.write(b"PSPLANET" + b"\x00" * 40)
    for args in (("export", out("bad.planet"), "--out", out("x.png")),
                 ("demo", "--video", out("no-such.mkv"), "--out", out("d")),
                 ("replay", out("no-such.mkv"), "--calib", CALIB, "--out", out("r")),
                 ("detect", out("no-such.png")),
                 ("import", out("bad.planet"), "--out", out("y.planet"))):
        p = subprocess.run([EXE, *args], capture_output=True, text=True)
        if p.returncode <= 0:
            fail(f"{' '.join(args)}: exit {p.returncode} (expected a refusal)")
        named = [a for a in args[1:] if a.startswith(OUT) and os.path.basename(a) in p.stderr]
        if not named:
            fail(f"{' '.join(args)}: the error does not name the file:\n{p.stderr}")
    with open(out("bad.yml"), "w") as f:
        f.write("%YAML:1.0\ncamera_matrix: [1, 2\n")
    p = subprocess.run([EXE, "replay", os.path.join(SRC, "data", "demo.mkv"), "--calib", out("bad.yml"),
                        "--out", out("r")],
                       capture_output=True, text=True)
    if p.returncode <= 0 or "bad.yml" not in p.stderr:
        fail(f"a malformed calibration was not refused by name: {p.returncode} {p.stderr}")
    p = subprocess.run([EXE, "export", out("tile.planet"), "--width", "-3", "--out", out("x.png")],
                       capture_output=True, text=True)
    if p.returncode <= 0:
        fail("a negative width was accepted")
    # The AR frames' sun: two finite numbers AZ,EL with the elevation in -90..90, else a refusal
    # that names the option, before anything is replayed.
    for sun in ("45", "45,nan", "1,2,3", "north,30", "10,95", "10,-91"):
        p = subprocess.run([EXE, "replay", os.path.join(SRC, "data", "demo.mkv"), "--calib", CALIB,
                            "--sun", sun, "--out", out("sun")], capture_output=True, text=True)
        if p.returncode <= 0 or "--sun" not in p.stderr:
            fail(f"--sun {sun} was not refused by name: {p.returncode} {p.stderr}")
    if os.path.exists(out("sun")):
        fail("a refused --sun still wrote its output folder")
    # A benchmark's settings are options of its own subcommand: a value that does not parse or is
    # out of range, or an option the benchmark does not have, is refused before anything runs,
    # naming the option and the value; `bench --help` names every benchmark's options.
    for args, named in ((("live", "--sides", "abc"), ("--sides", "abc")),
                        (("live", "--sides", "4097,1000"), ("--sides", "1000")),
                        (("live", "--seconds", "-3"), ("--seconds", "-3")),
                        (("track", "--scene", "baord"), ("--scene", "baord")),
                        (("track", "--tune", "1,2,3"), ("--tune",)),
                        (("track", "--search-every", "two"), ("--search-every", "two")),
                        (("deform", "--side", "1000"), ("--side", "1000")),
                        (("tessellate", "--charts", "latlong,torus"), ("--charts", "torus")),
                        (("occlusion", "--hand-off", "chroma,brite"), ("--hand-off", "brite")),
                        (("sand-tin", "--only", "sizes"), ("--only", "sizes")),
                        (("track", "--sides", "1025"), ("--sides",))):
        p = subprocess.run([EXE, "bench", *args, "--quick"], capture_output=True, text=True)
        if p.returncode <= 0 or p.stdout or not all(n in p.stderr for n in named):
            fail(f"bench {' '.join(args)} was not refused by name: exit {p.returncode}\n"
                 f"{p.stdout[-500:]}{p.stderr}")
    stdout, _ = run("bench", "--help")
    for option in ("--sides", "--texel-mm", "--board-scene", "--only", "--latitude", "--charts"):
        if option not in stdout:
            fail(f"bench --help does not name {option}:\n{stdout}")


def environment_after_exec(env, args):
    """Starts the program with env and returns the environment its running image holds
    (/proc/PID/environ, read until the process ends: after main re-executes itself, the
    re-executed image's)."""
    p = subprocess.Popen([EXE, *args], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                         env=env)
    seen = None
    while p.poll() is None:
        try:
            with open(f"/proc/{p.pid}/environ", "rb") as f:
                data = f.read()
            seen = data or seen  # a process that has ended (a zombie) reads empty
        except OSError:
            break
        time.sleep(0.005)
    p.wait()
    if p.returncode != 0:
        fail(f"{' '.join(args)}: exit {p.returncode}")
    if seen is None:
        fail(f"{' '.join(args)}: the process ended before its environment could be read")
    return dict(kv.split(b"=", 1) for kv in seen.split(b"\0") if b"=" in kv)


def group_openmp():
    # libgomp reads its spin count when it loads, so for the frame loops' commands and bench, main
    # sets GOMP_SPINCOUNT and executes itself again when the user set neither it nor
    # OMP_WAIT_POLICY (app/openmp_wait.hpp); a user's setting is kept, and other commands start
    # once. The commands last long enough for their environment to be read.
    args = ("bench", "charts", "--quick")
    base = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    got = environment_after_exec(base, args)
    if got.get(b"GOMP_SPINCOUNT") != b"30000" or b"OMP_WAIT_POLICY" in got:
        fail(f"with neither variable set the program ran with GOMP_SPINCOUNT="
             f"{got.get(b'GOMP_SPINCOUNT')}, OMP_WAIT_POLICY={got.get(b'OMP_WAIT_POLICY')}")
    for name, value in ((b"GOMP_SPINCOUNT", b"7"), (b"OMP_WAIT_POLICY", b"PASSIVE")):
        env = dict(base)
        env[name.decode()] = value.decode()
        got = environment_after_exec(env, args)
        other = b"OMP_WAIT_POLICY" if name == b"GOMP_SPINCOUNT" else b"GOMP_SPINCOUNT"
        if got.get(name) != value or other in got:
            fail(f"the user's {name.decode()}={value.decode()} was not kept as it was: "
                 f"{name.decode()}={got.get(name)}, {other.decode()}={got.get(other)}")
    got = environment_after_exec(base, ("markers", "--out", out("sheets"), "--paper", "a4"))
    if b"GOMP_SPINCOUNT" in got:
        fail("markers (no frame loop) was executed again with GOMP_SPINCOUNT set")


if __name__ == "__main__":
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    groups = {n[len("group_"):]: f for n, f in globals().items() if n.startswith("group_")}
    if GROUP not in groups:
        fail(f"unknown group {GROUP} (one of {', '.join(groups)})")
    groups[GROUP]()
    print(f"cli {GROUP}: passed")
