#pragma once
// How long OpenMP's worker threads spin after a parallel region, set for the program before
// libgomp reads it.

namespace ps::app {

// libgomp reads OMP_WAIT_POLICY and GOMP_SPINCOUNT once, when it is loaded, before main. Its
// default keeps every worker polling 300,000 times after each parallel region before it sleeps,
// which takes a core from the live loop's frame thread and the session's writer on a 2-core
// machine (docs/LIVE.md: a 4097² stroke's frame p99 19-23 ms against 7-9 ms at kSpinCount).
// For the commands that run a frame loop (live, demo, replay) and bench, which measures them,
// where the user set neither variable, this sets GOMP_SPINCOUNT to kSpinCount and executes the
// program again with the same arguments (about 0.1 s: the libraries load twice); a setting of the
// user's is kept. Returns without re-executing for other commands, where either variable is set,
// or where the program's own file cannot be executed again (libgomp keeps what it read).
void settleOpenMpWaiting(int argc, char** argv);

// Polls before a waiting worker sleeps. Not 0 (OMP_WAIT_POLICY=PASSIVE): an edit's parallel
// regions follow each other closely, and sleeping workers made bench deform's 8193² edits 11 %
// slower (docs/LIVE.md).
inline constexpr const char* kSpinCount = "30000";

}  // namespace ps::app
