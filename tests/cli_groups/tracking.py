"""`cli_synth_detect` and `cli_markers`: synthetic videos, detection, printable sheets read back."""
import json
import math
import os

from cli_groups.common import CALIB, SRC, fail, run, out, is_png


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
