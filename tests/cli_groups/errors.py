"""`cli_errors`: bad input refused with a message that names the file and what is wrong."""
import os
import subprocess

from cli_groups.common import CALIB, EXE, SRC, OUT, fail, run, out


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
