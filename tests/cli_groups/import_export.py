"""`cli_import_export` and `cli_road`: heightmaps in and out (raw, PNG, GeoTIFF, PDS3), meshes,
TINs, overlays, and roads from stroke files."""
import json
import math
import os
import struct
import subprocess

from cli_groups.common import EXE, SRC, fail, run, out, write_raw, read_raw, gdalinfo, write_pds3


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

    # Near the poles the chart bends a straight grid edge: a road laid in the grid (a stencil) has
    # its edges halved until they stray at most --error (200 m) from its path (25 km edges 2
    # degrees from the octahedral south pole strayed 2.1 km before 2026-12-07), and is cut in a
    # piece on each side of a glued side it crosses (its vertices on the side within 50 m of its
    # footprint, at their twins' places). A stitch on a sphere goes in the road's own plane since
    # 2026-12-08 (tin/plane_stitch): one piece, nothing halved, every vertex on its footprint
    # (draped in the grid before: within 1 m where laid whole, 50 m where cut; put on the mesh's
    # flat 24 km triangles at their grid points before 2026-12-07, they slid up to 210 m).
    for planet, at, crosses in (("globe_octa", (-45, 0, 0), True), ("globe_octa", (-45, 0, 90), True),
                                ("globe_octa", (-30, -90, 35), True), ("globe", (10, 180, 90), True),
                                ("globe_octa", (-88, 30, 0), True), ("globe_octa", (89, 0, 0), False),
                                ("globe", (75, 20, 60), False), ("globe_octa", (0, -90, 0), True)):
        where = ",".join(str(a) for a in at)
        for mode in ("stitch", "stencil"):
            stdout, _ = run("overlay", out(f"{planet}.planet"), out("strip.obj"), "--at", where, "--error", "200",
                            "--mode", mode, "--out", out("folded_road.obj"))
            r = json.loads(stdout)
            worst, faces = off_footprint(out("folded_road.obj"), *at, 1737400)
            closed = r["euler"] == 2 and r["border_edges"] == 0 and r["non_manifold_edges"] == 0
            if mode == "stitch" and r["stitched_in"] == "road plane":
                ok = closed and faces >= 16 and worst <= 1 and r["road_pieces"] == 1 and r["road_stray_m"] == 0
            elif mode == "stitch":  # the grid's, where the plane cannot see the mesh one to one
                ok = closed and faces >= 16 and worst <= (50 if crosses else 1) and r["road_undraped_edges"] == 0
            else:
                ok = (closed and faces >= 16 and worst <= (50 if crosses else 1)
                      and (r["road_pieces"] > 1) == crosses and r["road_stray_m"] <= 200)
            if not ok:
                fail(f"a road at {where} on {planet}, {mode}: {r}, {faces} road triangles, {worst:.0f} m off its footprint")


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
