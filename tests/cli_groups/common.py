"""What every group of tests/cli_commands.py shares: the command line it was started with, running
the program, and small file formats written and read with Python's standard library."""
import json
import math
import os
import struct
import subprocess
import sys
import time

GROUP, EXE, SRC, OUT = sys.argv[1:5]
BENCH = sys.argv[5] if len(sys.argv) > 5 else ""
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
    start = time.monotonic()
    p = subprocess.run([EXE, *args], capture_output=True, text=True, env=env)
    if os.environ.get("PS_CLI_TIMES"):  # where a group's time goes (docs/CI.md)
        print(f"{time.monotonic() - start:7.2f} s  {' '.join(args)}", file=sys.stderr)
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
