// A test hook for the kill-anywhere and Slurm tests (tests/cli_record_kill_anywhere_test.cc,
// tests/slurm_test.cc): the places where record makes a file final (the encoder's flush, and
// before and after each rename of a temporary onto its final name) are numbered per process as
// they are reached.
//   FETCHSCOPE_TEST_KILL_AT=N     the process SIGKILLs itself at the Nth point (1 = the first)
//   FETCHSCOPE_TEST_KILL_AT=list  each point is printed to stderr ("fetchscope: kill point N:
//                                 WHAT"), so that a test can count them
//   FETCHSCOPE_TEST_KILL_HOW=pause  at the Nth point, say so on stderr ("fetchscope: paused at
//                                 kill point N") and wait (up to 120 s) for SIGINT/SIGTERM
//                                 instead of dying, then go on: a test can signal a run it
//                                 knows to be in the middle of writing
//   FETCHSCOPE_TEST_KILL_RESUME=PATH  with pause: also go on (unsignalled) once PATH exists, so
//                                 that a test can change the world between two points
//   FETCHSCOPE_TEST_KILL_IF=NAME=VALUE[,NAME=VALUE...]  only in a process whose environment has
//                                 each NAME=VALUE (NAME= : unset or empty); e.g.
//                                 SLURM_ARRAY_TASK_ID=1,SLURM_RESTART_COUNT= : one task of an
//                                 array, on its first attempt
// Unset (as always outside the tests), a kill point costs one load of a static.
#pragma once

namespace fetchscope {

/// Counts one kill point, `what` naming it ("video flush", "file renamed", ...).
void KillPoint(const char* what);

}  // namespace fetchscope
