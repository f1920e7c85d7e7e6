#!/bin/sh
# ctest live_smoke: `planetsculpt live` on 30 frames of the demo video in a window under Xvfb
# must exit 0, say it drew 30 frames, show the camera image in the window (a marker is found in
# its screenshot) and save a planet file that `live --planet` loads again; Ctrl-C (SIGINT) in
# the window's loop saves the planet too, and so does a run that outlasts the video (recorded
# with --record; the recording replays to the same planet); a killed session's stroke journal
# is left alone, recovered or discarded as asked, and refused by another planet; the panel's
# actions (scripted with --at) export, record and quit; a session with settings changed while
# recording replays with its sidecar to the same planet, and without it to another.
# Exit 77 (ctest SKIP_RETURN_CODE) when xvfb-run is not installed.
# Usage: live_smoke.sh EXE SOURCE_DIR OUT_DIR
set -u
exe=$1 src=$2 out=$3
if ! command -v xvfb-run >/dev/null 2>&1; then
  echo "SKIP: xvfb-run not found (apt install xvfb xauth)"
  exit 77
fi
rm -rf "$out" && mkdir -p "$out" || exit 1
# Under the asan preset: Xlib, GLX and GLFW keep allocations until exit that are not ours, so
# leak checking is off for the windowed runs (memory errors still abort); the unit tests cover
# our code's leaks.
ASAN_OPTIONS="${ASAN_OPTIONS:-}${ASAN_OPTIONS:+:}detect_leaks=0"
export ASAN_OPTIONS
# The test-only --at actions `interrupt` (SIGINT) and `crash` (SIGKILL) exist only with this set.
PS_TEST_ACTIONS=1
export PS_TEST_ACTIONS
fail() { echo "FAIL: $*"; cat "$out/live.txt" 2>/dev/null; exit 1; }
run() {  # run LOG ARGS...: the live command in a fresh virtual screen
  log=$1
  shift
  xvfb-run -a -s "-screen 0 1280x1024x24" "$exe" live --video "$src/data/demo.mkv" \
    --calib "$src/calib/synthetic-640x480.yml" --grid 1025 "$@" >"$log" 2>&1
}
run "$out/live.txt" --frames 30 --out "$out/a" --screenshot "$out/window.png"
rc=$?
[ $rc -eq 0 ] || fail "live exited with $rc"
grep -q "live: 30 frames" "$out/live.txt" || fail "no 'live: 30 frames' line"
[ -s "$out/a/planet.planet" ] || fail "no $out/a/planet.planet"
[ -s "$out/window.png" ] || fail "no screenshot $out/window.png"
"$exe" detect "$out/window.png" >"$out/detect.txt" 2>&1 || fail "detect on the screenshot failed"
grep -q '"id":' "$out/detect.txt" || { cat "$out/detect.txt"; fail "no marker in the window"; }
# The saved file is a planet: a second session starts from it and saves it again unchanged
# (3 frames of the video's start: nobody touches the planet there; the panel's hand mask off).
run "$out/live2.txt" --frames 3 --planet "$out/a/planet.planet" --out "$out/b" --no-hand-mask
rc=$?
[ $rc -eq 0 ] || { cat "$out/live2.txt"; fail "live --planet exited with $rc"; }
cmp -s "$out/a/planet.planet" "$out/b/planet.planet" || fail "the reloaded planet changed"
# Past the video's end (346 frames): the window stays, the planet is kept and saved. The run
# records the frames it processed (--record into a folder: the next recording-NNN.mkv there);
# replaying that recording sculpts the same planet, byte for byte.
run "$out/live4.txt" --frames 350 --out "$out/d" --record "$out/d/recs/"
rc=$?
[ $rc -eq 0 ] || { cat "$out/live4.txt"; fail "live past the video's end exited with $rc"; }
grep -q "live: 350 frames" "$out/live4.txt" || { cat "$out/live4.txt"; fail "no 'live: 350 frames'"; }
[ -s "$out/d/planet.planet" ] || fail "no $out/d/planet.planet after the video ended"
grep -q "recorded 346 frames to $out/d/recs/recording-001.mkv" "$out/live4.txt" ||
  { cat "$out/live4.txt"; fail "no 'recorded 346 frames' line"; }
[ "$(stat -c %s "$out/d/planet.journal")" -eq 64 ] || fail "the journal was not restarted at the end"
"$exe" replay "$out/d/recs/recording-001.mkv" --calib "$src/calib/synthetic-640x480.yml" --grid 1025 \
  --out "$out/d/replay" >"$out/replay.txt" 2>&1 || { cat "$out/replay.txt"; fail "replay of the recording failed"; }
grep -q '"frames": *346' "$out/d/replay/summary.json" || fail "the recording did not replay 346 frames"
cmp -s "$out/d/planet.planet" "$out/d/replay/planet.planet" ||
  fail "replaying the recording sculpted another planet than the live session"
# A session whose settings change while it records (--at FRAME:SETTING=VALUE, as if set in the
# panel, the sand's material among them; undo and redo, the last two after the video's end): the recording's sidecar
# (session.mkv.session.jsonl) makes the replay sculpt the same planet, byte for byte; without it
# (--no-session) the replay sculpts another; a damaged sidecar is refused naming its line.
run "$out/live12.txt" --frames 350 --out "$out/i" --record "$out/i/session.mkv" \
  --at 50:radius_km=400 --at 80:strength_m=1500 --at 100:size_cm=6.5 --at 130:undo \
  --at 140:redo --at 170:mode=lower --at 200:tool=displace --at 210:material=pebbles --at 230:tool=brush \
  --at 290:spin_deg=15 --at 347:undo --at 348:redo --at 349:undo ||
  { cat "$out/live12.txt"; fail "live with scripted settings failed"; }
side="$out/i/session.mkv.session.jsonl"
[ "$(wc -l <"$side")" -ge 11 ] || { cat "$side"; fail "the sidecar lacks the session's changes"; }
grep -q '"frame":51,.*"brush_radius_m":400000' "$side" || { cat "$side"; fail "no r_d change at frame 51"; }
grep -q '"frame":211,"material":"pebbles"' "$side" || { cat "$side"; fail "no material change at frame 211"; }
grep -q '"frame":346,"event":"redo"' "$side" ||
  { cat "$side"; fail "no redo after the video's end"; }
"$exe" replay "$out/i/session.mkv" --calib "$src/calib/synthetic-640x480.yml" \
  --out "$out/i/replay" >"$out/replay3.txt" 2>&1 || { cat "$out/replay3.txt"; fail "replay with the sidecar failed"; }
grep -q "settings from the session sidecar $side" "$out/replay3.txt" || { cat "$out/replay3.txt"; fail "the sidecar was not used"; }
grep -q '"session_changes": *1[0-9]' "$out/i/replay/summary.json" || fail "the sidecar's changes were not applied"
grep -q '"warnings": *\[\]' "$out/i/replay/summary.json" || { cat "$out/i/replay/summary.json"; fail "the replay warned"; }
cmp -s "$out/i/planet.planet" "$out/i/replay/planet.planet" ||
  fail "replaying the recording with its sidecar sculpted another planet than the live session"
"$exe" replay "$out/i/session.mkv" --calib "$src/calib/synthetic-640x480.yml" --grid 1025 --no-session \
  --out "$out/i/plain" >"$out/replay4.txt" 2>&1 || { cat "$out/replay4.txt"; fail "replay --no-session failed"; }
cmp -s "$out/i/planet.planet" "$out/i/plain/planet.planet" &&
  fail "the replay without the sidecar sculpted the same planet: the changes did nothing"
sed '3s/.*/{"frame": 99, "sigma": "wide"}/' "$side" >"$out/i/bad.jsonl"
"$exe" replay "$out/i/session.mkv" --calib "$src/calib/synthetic-640x480.yml" --session "$out/i/bad.jsonl" \
  --out "$out/i/bad" >"$out/replay5.txt" 2>&1 && fail "a damaged sidecar was accepted"
grep -q "$out/i/bad.jsonl:3: \"sigma\" is not a number" "$out/replay5.txt" ||
  { cat "$out/replay5.txt"; fail "the damaged sidecar's message does not name file and line"; }
[ -e "$out/i/bad/planet.planet" ] && fail "a planet was written despite the damaged sidecar"
# The sidecar names the chart the session sculpted (the default planet's: octahedral). One that
# names none (written before sidecars named charts, when every new planet was lat-long) replays
# onto lat-long and says so once: a lat-long session's sidecar with its chart taken out replays
# to the session's planet, byte for byte.
grep -q '"chart":"octahedral"' "$side" || { cat "$side"; fail "the sidecar does not name the octahedral chart"; }
run "$out/live13.txt" --frames 60 --chart latlong --out "$out/k" --record "$out/k/old.mkv" ||
  { cat "$out/live13.txt"; fail "live --chart latlong --record failed"; }
grep -q '"chart":"latlong",' "$out/k/old.mkv.session.jsonl" || fail "the lat-long sidecar does not name its chart"
sed -i 's/"chart":"latlong",//' "$out/k/old.mkv.session.jsonl"
"$exe" replay "$out/k/old.mkv" --calib "$src/calib/synthetic-640x480.yml" --out "$out/k/replay" \
  >"$out/replay6.txt" 2>&1 || { cat "$out/replay6.txt"; fail "replay of a sidecar naming no chart failed"; }
[ "$(grep -c 'names no chart: replaying onto lat-long' "$out/replay6.txt")" -eq 1 ] ||
  { cat "$out/replay6.txt"; fail "the replay did not say once that the sidecar names no chart"; }
cmp -s "$out/k/planet.planet" "$out/k/replay/planet.planet" ||
  fail "a sidecar naming no chart did not replay onto the lat-long planet it was recorded on"
# Ctrl-C (SIGINT) while the window is open (sent by the app to itself at window frame 20): exits 0
# and saves the planet.
# Without PS_TEST_ACTIONS the test actions are not part of the command surface: refused.
env -u PS_TEST_ACTIONS "$exe" live --video "$src/data/demo.mkv" --calib "$src/calib/synthetic-640x480.yml" \
  --out "$out/x" --at 5:crash \
  >"$out/refused.txt" 2>&1 && fail "--at 5:crash was accepted without PS_TEST_ACTIONS"
grep -q "expected FRAME:ACTION" "$out/refused.txt" || { cat "$out/refused.txt"; fail "no refusal for --at 5:crash"; }
run "$out/live3.txt" --out "$out/c" --at 20:interrupt
rc=$?
[ $rc -eq 0 ] || { cat "$out/live3.txt"; fail "live after SIGINT exited with $rc"; }
grep -q "interrupted; saving" "$out/live3.txt" || fail "no 'interrupted; saving' line"
[ -s "$out/c/planet.planet" ] || fail "SIGINT did not save $out/c/planet.planet"
# A crash (SIGKILL) once the stroke journal holds a stroke: the next start neither recovers nor
# discards on its own (both files untouched, a line naming the journal), --recover applies it,
# --discard-journal sets it aside, and the journal is refused by another planet's directory.
# The crash is scripted at window frame 200 (the demo's first strokes have ended by then).
run "$out/live5.txt" --out "$out/e" --autosave-s 0 --at 200:crash
size=$(stat -c %s "$out/e/planet.journal" 2>/dev/null || echo 0)
[ "$size" -gt 64 ] || { cat "$out/live5.txt"; fail "no stroke reached the journal before the crash"; }
cp "$out/e/planet.journal" "$out/journal.crash"
cp "$out/e/planet.planet" "$out/planet.crash"
mkdir -p "$out/f" && cp "$out/e/planet.journal" "$out/e/planet.planet" "$out/f/"
run "$out/live6.txt" --frames 3 --out "$out/e"
rc=$?
[ $rc -eq 0 ] || { cat "$out/live6.txt"; fail "live with a journal left exited with $rc"; }
grep -q "was left untouched" "$out/live6.txt" || { cat "$out/live6.txt"; fail "no 'left untouched' line"; }
grep -q "$out/e/planet.journal" "$out/live6.txt" || fail "the message does not name the journal"
cmp -s "$out/e/planet.journal" "$out/journal.crash" || fail "the journal changed without an answer"
cmp -s "$out/e/planet.planet" "$out/planet.crash" || fail "the planet changed without an answer"
run "$out/live7.txt" --frames 3 --out "$out/e" --recover
rc=$?
[ $rc -eq 0 ] || { cat "$out/live7.txt"; fail "live --recover exited with $rc"; }
grep -q "live: recovered [1-9][0-9]* records* of $out/e/planet.journal" "$out/live7.txt" ||
  { cat "$out/live7.txt"; fail "no 'recovered' line"; }
cmp -s "$out/e/planet.planet" "$out/planet.crash" && fail "the recovered planet was not saved"
[ "$(stat -c %s "$out/e/planet.journal")" -eq 64 ] || fail "the journal was not restarted after recovery"
run "$out/live8.txt" --frames 3 --out "$out/f" --discard-journal
rc=$?
[ $rc -eq 0 ] || { cat "$out/live8.txt"; fail "live --discard-journal exited with $rc"; }
cmp -s "$out/f/planet.journal.discarded" "$out/journal.crash" || fail "the discarded journal was not kept"
# Another planet (a 513² grid) in the directory the journal is copied to.
xvfb-run -a -s "-screen 0 1280x1024x24" "$exe" live --video "$src/data/demo.mkv" \
  --calib "$src/calib/synthetic-640x480.yml" --grid 513 --frames 2 --out "$out/g" >"$out/live9.txt" 2>&1 ||
  { cat "$out/live9.txt"; fail "live --grid 513 failed"; }
cp "$out/journal.crash" "$out/g/planet.journal"
xvfb-run -a -s "-screen 0 1280x1024x24" "$exe" live --video "$src/data/demo.mkv" \
  --calib "$src/calib/synthetic-640x480.yml" --grid 513 --frames 2 --out "$out/g" >"$out/live10.txt" 2>&1 ||
  { cat "$out/live10.txt"; fail "live with another planet's journal failed"; }
grep -q "$out/g/planet.journal was written for another planet" "$out/live10.txt" ||
  { cat "$out/live10.txt"; fail "another planet's journal was not refused by name"; }
cmp -s "$out/g/planet.journal.refused" "$out/journal.crash" || fail "the refused journal was not kept"
# The panel's actions at scripted window frames (--at; the keys map to the same actions):
# export heightmap, sidecar and mesh to OUT/exports/, start and stop a recording that replays,
# save and quit.
run "$out/live11.txt" --out "$out/h" --at 40:export --at 60:record --at 250:record --at 300:quit ||
  { cat "$out/live11.txt"; fail "live with scripted actions failed"; }
grep -q "live: exported $out/h/exports/planet-001.png" "$out/live11.txt" ||
  { cat "$out/live11.txt"; fail "the export action did not export"; }
for f in planet-001.png planet-001.png.json planet-001.glb; do
  [ -s "$out/h/exports/$f" ] || fail "no $out/h/exports/$f"
done
grep -q "live: recorded 190 frames to $out/h/recording-001.mkv" "$out/live11.txt" ||
  { cat "$out/live11.txt"; fail "the record action did not record frames 60-249"; }
"$exe" replay "$out/h/recording-001.mkv" --calib "$src/calib/synthetic-640x480.yml" --grid 1025 \
  --out "$out/h/replay" >"$out/replay2.txt" 2>&1 || { cat "$out/replay2.txt"; fail "the recording does not replay"; }
grep -q "saved $out/h/planet.planet" "$out/live11.txt" || fail "quit did not save"
echo "PASS"
