// SIGINT/SIGTERM as a request to stop: long commands finish the file in progress.
#pragma once

#include <signal.h>

namespace fetchscope {

/// Makes SIGINT and SIGTERM request a stop instead of killing the process, so long commands
/// (record, golden update) can finish the file in progress; clears any earlier request.
void InstallStopSignals();

/// The signal that requested a stop (SIGINT or SIGTERM), or 0. Safe from any thread.
int StopSignal();

/// A descriptor that becomes readable when a stop is requested and stays readable until the
/// next InstallStopSignals (a self-pipe written by the handler, whichever thread runs it), for
/// poll sets; -1 before InstallStopSignals in this process.
int StopSignalFd();

/// SIGINT and SIGTERM, the signals InstallStopSignals handles.
sigset_t StopSignalSet();

/// Blocks SIGINT and SIGTERM in the calling thread while it lives; wait_mask() is the mask to pass
/// to ppoll, so that a stop signal is taken only inside the wait and cannot slip in between the
/// check of StopSignal() and the wait.
class StopSignalBlock {
 public:
  StopSignalBlock();
  ~StopSignalBlock();
  StopSignalBlock(const StopSignalBlock&) = delete;
  StopSignalBlock& operator=(const StopSignalBlock&) = delete;
  /// The mask to wait with: the one before the block, with the stop signals unblocked.
  const sigset_t* wait_mask() const { return &wait_; }

 private:
  sigset_t old_;
  sigset_t wait_;
};

}  // namespace fetchscope
