// SIGINT/SIGTERM as a request to stop: long commands finish the file in progress.
#pragma once

namespace fetchscope {

/// Makes SIGINT and SIGTERM request a stop instead of killing the process, so long commands
/// (record, golden update) can finish the file in progress; clears any earlier request.
void InstallStopSignals();

/// The signal that requested a stop (SIGINT or SIGTERM), or 0. Safe from any thread.
int StopSignal();

}  // namespace fetchscope
