// The parts of `fetchscope bench`, one per pipeline stage.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "src/assets.h"

namespace fetchscope::cli {

/// Peak resident set size of this process so far, MiB.
double PeakRssMiB();
/// CPU model, cores, memory, OS: the machine every figure was measured on.
nlohmann::json MachineJson();
/// Env steps/s per task beside the raw mj_step bound.
nlohmann::json BenchSim(const AssetSource& assets, double budget_s);
/// Render+readback frames/s per backend and size, beside mujoco-record.
nlohmann::json BenchRender(const AssetSource& assets, const std::string& backends, double budget_s, bool peers);
/// Encode frames/s per codec.
nlohmann::json BenchEncode(double budget_s);
/// Record seconds per frame, beside mujoco-record + ffmpeg.
nlohmann::json BenchRecord(const AssetSource& assets, const std::string& backends, double budget_s, bool peers);

}  // namespace fetchscope::cli
