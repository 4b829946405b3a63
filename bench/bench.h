// The parts of `fetchscope bench`, one per pipeline stage.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "src/assets.h"

namespace fetchscope::bench {

/// Peak resident set size of this process so far, MiB.
double PeakRssMiB();
/// CPU model, cores, memory, OS: the machine every figure was measured on.
nlohmann::json MachineJson();
/// Env steps/s per task beside the raw mj_step bound.
nlohmann::json BenchSim(const AssetSource& assets, double budget_s);
/// Render+readback frames/s per backend and size, beside mujoco-record.
nlohmann::json BenchRender(const AssetSource& assets, const std::string& backends, double budget_s,
                           bool peers);
/// Encode frames/s per codec.
nlohmann::json BenchEncode(double budget_s);
/// Record seconds per frame (msaa auto beside 4), --jobs 1 against --jobs 2 where record has
/// --jobs, beside mujoco-record + ffmpeg.
nlohmann::json BenchRecord(const AssetSource& assets, const std::string& backends, double budget_s,
                           bool peers);
/// What a user needs to size a job on this node, side by side: its cores, GPUs and encoder;
/// one context's render frames/s (sync against async readback, msaa auto and 0) at
/// `width` x `height`; whole record runs at --jobs 1, cores/2 and cores, worker processes
/// against threads.
nlohmann::json BenchNode(const AssetSource& assets, const std::string& backends, double budget_s,
                         int width = 480, int height = 480);
/// The --jobs, --worker-mode (and --msaa when 0 won) of BenchNode's fastest "record" row:
/// {jobs, worker_mode, msaa_requested, frames_per_s, flags: "--jobs 8 --worker-mode process",
/// why}; {none: why} when no record run finished.
nlohmann::json NodeRecommendation(const nlohmann::json& record_rows);
/// serve's frame budget at `width` x `height` on `backend` (bench/serve.cc): render + encode per
/// frame (JPEG and PNG), frames/s of one, two and four pages dragging over HTTP, a live key step,
/// an episode's first view and a seek in it.
nlohmann::json BenchServe(const AssetSource& assets, const std::string& backend, double budget_s,
                          int width, int height);
/// Pixel datasets (issue 45) side by side, each a child of this binary: `rollout --minari` with
/// one --obs-camera at `size` x `size` rgb, the same record of that camera alone (--overlay none,
/// webm, no sheets), and rollout without images: steps/s, CPU per step and peak RSS of each, and
/// the images-into-a-dataset rate against record's frames/s.
nlohmann::json BenchDataset(const AssetSource& assets, const std::string& backends, int episodes,
                            int size);

/// Images to an exec: policy (issue 46), each a child of this binary on FetchReach-v4 with
/// external_camera_0 rgb at `size` (WxH): rollout --policy zero without images and into a Minari
/// dataset, and a Python child (`python`) reading only lines, then the images as bytes, then as
/// numpy arrays: steps/s and CPU per step of each, the ratio of the last to the dataset, and the
/// CPU per step of each part (the Python loop, the images to Python, numpy).
nlohmann::json BenchExecImages(const AssetSource& assets, const std::string& backends, int episodes,
                               const std::string& size, const std::string& python);

/// What a randomized look (issue 49) costs a recorded frame's CPU: `repeats` pairs of record runs
/// of this binary (FetchPush-v4, random, `episodes` episodes at 480x480, --jobs 1, on `backend`,
/// LP_NUM_THREADS=0), plain and --randomize colors,textures,lighting,camera alternating; per frame
/// the renderer's stages outside GL (scene, hud, copy), the look's own (its draw and texture
/// upload), their sum, the whole of outside GL and GL, each plain beside randomized (mean, range,
/// every run) with the ratio of the means.
nlohmann::json BenchLook(const AssetSource& assets, const std::string& backend, int episodes,
                         int repeats);

/// One record run of about `target_frames` frames at 640x480 on the first of `backends`, its
/// resident set sampled every `interval_s`: whether memory stays flat over a long run.
nlohmann::json BenchSoak(const AssetSource& assets, const std::string& backends, int target_frames,
                         double interval_s);

}  // namespace fetchscope::bench
