"""`cli_openmp`: the frame loops' commands re-executed with a gentler OpenMP spin count."""
import os
import subprocess
import time

from cli_groups.common import EXE, fail, out


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
