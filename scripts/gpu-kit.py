#!/usr/bin/env python3
"""Builds the kit that runs build/release/planetsculpt on a bare machine (the GPU device).

The binary's shared-library closure on Debian 12 is ~245 libraries / 296 MB (GDAL, FFmpeg's codec
libraries, GStreamer, ICU...), 86 MB as .tar.xz: too big to travel. `bench render` and `bench
frame` need few of them, so the libraries listed in STUB (and what only they pull in) are
replaced by stubs: same SONAME, same exported symbols and symbol versions, no dependencies, every
function a trap that prints "gpukit: stub called: LIB SYMBOL" and exits 134. The loader is
satisfied; a code path that really needs a stubbed library fails loudly instead of silently.

Left out altogether: glibc's own libraries and the GL/EGL dispatch libraries (glvnd, from the
device's .gl debs and its NVIDIA driver). libstdc++/libgcc_s/libdrm go to fallback/ (the script
uses them only where the device has none or an older one).

Usage: python3 scripts/gpu-kit.py  (from the repo root, after the release build; stages the kit
in /tmp/gpukit-stage/kit and packs it into .gpukit/kit.tar.xz, which scripts/gpu-measure.sh
unpacks on the device)
"""
import os
import re
import shutil
import subprocess
import sys

ROOT = os.getcwd()
BINARY = os.path.join(ROOT, "build/release/planetsculpt")
KIT = "/tmp/gpukit-stage/kit"
PACKED = os.path.join(ROOT, ".gpukit/kit.tar.xz")

GLIBC = re.compile(r"^(ld-linux|libc|libm|libpthread|libdl|librt|libresolv|libutil|libmvec)[.-]")
GL = re.compile(r"^lib(GL|EGL|GLX|GLdispatch|OpenGL|GLESv1_CM|GLESv2|gbm)\.so")
FALLBACK = re.compile(r"^lib(stdc\+\+|gcc_s|drm)\.so")

STUB = """
libgdal.so.32
libgstbase-1.0.so.0 libgstreamer-1.0.so.0 libgstapp-1.0.so.0 libgstriff-1.0.so.0
libgstpbutils-1.0.so.0 libgstvideo-1.0.so.0 libgstaudio-1.0.so.0 libgobject-2.0.so.0
libglib-2.0.so.0 libgphoto2.so.6 libgphoto2_port.so.12 libdc1394.so.25
libgdcmMSFF.so.3.0 libgdcmDSED.so.3.0 libOpenEXR-3_1.so.30
librsvg-2.so.2 libzvbi.so.0 libcodec2.so.1.0 libx264.so.164 libSvtAv1Enc.so.1
librav1e.so.0 libjxl.so.0.7 libjxl_threads.so.0.7 libxvidcore.so.4 libshine.so.3
libtwolame.so.0 libgsm.so.1 libspeex.so.1 libtheoraenc.so.1 libtheoradec.so.1 libvorbis.so.0
libvorbisenc.so.2 libmfx.so.1 libmp3lame.so.0 libopus.so.0
libchromaprint.so.1 libbluray.so.2 librabbitmq.so.4 librist.so.4
libsrt-gnutls.so.1.5 libssh-gcrypt.so.4 libzmq.so.5
libicuuc.so.72 libopencv_dnn.so.406 libcairo.so.2 libglfw.so.3
""".split()
# Kept real, since `bench frame` calls them: libgme and libopenmpt (FFmpeg's format probes) and
# libx265 (libavcodec's static codec initialisation asks x265_api_get).
STUB += [s for s in os.environ.get("KIT_STUB_MORE", "").split() if s]
STUB = [s for s in STUB if s not in os.environ.get("KIT_STUB_LESS", "").split()]


def run(*cmd):
    return subprocess.run(cmd, check=True, capture_output=True, text=True).stdout


def needed(path):
    return re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", run("readelf", "-dW", path))


def soname(path):
    m = re.search(r"\(SONAME\)\s+Library soname: \[(.+?)\]", run("readelf", "-dW", path))
    return m.group(1) if m else os.path.basename(path)


def resolver():
    table = {}
    for line in run("ldconfig", "-p").splitlines():
        m = re.match(r"\s+(\S+) \((.*?)\) => (\S+)", line)
        if m and "x86-64" in m.group(2) and m.group(1) not in table:
            table[m.group(1)] = m.group(3)
    return table


def make_stub(lib, path, out_dir):
    """Writes out_dir/lib: a stub with lib's SONAME, exports and symbol versions."""
    versions = []
    in_def = False
    for line in run("readelf", "-VW", path).splitlines():
        if "Version definition section" in line:
            in_def = True
        elif "Version needs section" in line or "Version symbols section" in line:
            in_def = False
        elif in_def:
            m = re.search(r"Flags: (\S+)\s+Index: \d+\s+Cnt: \d+\s+Name: (\S+)", line)
            if m and m.group(1) != "BASE":
                versions.append(m.group(2))
    by_version = {v: [] for v in versions}
    asm = [".text", "__kitstub_trap:", "  mov $2, %edi", "  mov $1, %eax", "  syscall",
           "  mov $134, %edi", "  mov $231, %eax", "  syscall", "  hlt"]
    strings = []
    skip = {"_init", "_fini", "_edata", "_end", "__bss_start"}
    n = 0
    for line in run("readelf", "--dyn-syms", "-W", path).splitlines():
        f = line.split()
        if len(f) < 8 or not f[0][:-1].isdigit() or f[6] in ("UND", "ABS"):
            continue
        size, kind, bind, name = int(f[2], 0), f[3], f[4], f[7]
        if bind not in ("GLOBAL", "WEAK", "UNIQUE"):
            continue
        if "@@" in name:
            name, version = name.split("@@")
            by_version[version].append(name)
        elif "@" in name:
            continue  # a hidden (old) version: nothing built against this release binds to it
        if name in skip:
            continue
        q = '"' + name + '"'
        n += 1
        if kind in ("FUNC", "IFUNC", "NOTYPE"):
            msg = f"gpukit: stub called: {lib} {name}\\n"
            strings.append(f'.Ls{n}: .ascii "{msg}"')
            length = len(msg) - 1  # the \\n escape is one byte
            asm += [f".globl {q}", f".type {q},@function", f"{q}:",
                    f"  lea .Ls{n}(%rip), %rsi", f"  mov ${length}, %edx", "  jmp __kitstub_trap"]
        elif kind == "TLS":
            asm += [".section .tbss,\"awT\",@nobits", ".balign 16", f".globl {q}",
                    f".type {q},@tls_object", f".size {q}, {max(size, 1)}", f"{q}: .zero {max(size, 1)}",
                    ".text"]
        else:  # OBJECT, COMMON
            asm += [".bss", ".balign 16", f".globl {q}", f".type {q},@object",
                    f".size {q}, {max(size, 1)}", f"{q}: .zero {max(size, 1)}", ".text"]
    asm += [".section .rodata"] + strings + ['.section .note.GNU-stack,"",@progbits']
    work = os.path.join(out_dir, ".stub-" + lib)
    with open(work + ".s", "w") as f:
        f.write("\n".join(asm) + "\n")
    cmd = ["gcc", "-shared", "-nostdlib", "-o", os.path.join(out_dir, lib), work + ".s",
           f"-Wl,-soname,{lib}", "-Wl,-z,noexecstack"]
    if versions:
        with open(work + ".map", "w") as f:
            for v in versions:
                syms = "".join(f' "{s}";' for s in by_version[v])
                f.write(f"{v} {{ global:{syms} }};\n" if syms else f"{v} {{ }};\n")
        cmd.append(f"-Wl,--version-script={work}.map")
    subprocess.run(cmd, check=True)
    for ext in (".s", ".map"):
        if os.path.exists(work + ext):
            os.remove(work + ext)


def main():
    where = resolver()
    shutil.rmtree(KIT, ignore_errors=True)
    os.makedirs(os.path.join(KIT, "lib"))
    os.makedirs(os.path.join(KIT, "fallback"))
    subprocess.run(["strip", "--strip-unneeded", "-o", os.path.join(KIT, "planetsculpt"), BINARY],
                   check=True)
    seen, todo, stubs = set(), list(needed(BINARY)), []
    while todo:
        lib = todo.pop()
        if lib in seen or GLIBC.match(lib):
            continue
        seen.add(lib)
        path = where.get(lib)
        if not path:
            sys.exit(f"make-kit: {lib} not found on this machine")
        if GL.match(lib):  # from the device (glvnd debs), but what it needs comes with the kit
            todo += needed(path)
            continue
        if lib in STUB:
            make_stub(lib, path, os.path.join(KIT, "lib"))
            stubs.append(lib)
            continue
        dest = "fallback" if FALLBACK.match(lib) else "lib"
        shutil.copy(os.path.realpath(path), os.path.join(KIT, dest, lib))
        todo += needed(path)
    unused = sorted(set(STUB) - set(stubs))
    if unused:
        print("make-kit: not in the closure (no stub made):", " ".join(unused))
    real = sorted(lib for lib in seen - set(stubs) if not GL.match(lib))
    print(f"make-kit: {len(real)} libraries copied, {len(stubs)} stubs")
    with open(os.path.join(KIT, "KIT-INFO"), "w") as f:
        f.write("built " + run("date", "-u", "+%Y-%m-%dT%H:%M:%SZ"))
        f.write("from " + run("git", "-C", ROOT, "log", "-1", "--format=%H %s"))
        f.write("uncommitted changes in the build:\n" + run("git", "-C", ROOT, "status", "--short",
                                                           "--untracked-files=no"))
        f.write("stubs: " + " ".join(sorted(stubs)) + "\n")
    subprocess.run(f"tar -C {os.path.dirname(KIT)} -cf - kit | xz -9 -T2 > {PACKED}", shell=True,
                   check=True)
    print(f"make-kit: {PACKED}: {os.path.getsize(PACKED)} bytes "
          f"({run('du', '-sb', KIT).split()[0]} unpacked)")


if __name__ == "__main__":
    main()
