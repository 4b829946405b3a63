// CPU time, not wall time: the per-stage account of a recorded frame (record's manifest
// timings_s.cpu_s, bench --what record). Thread CPU clocks count only the calling thread's
// time on a core, so they hold steady on a busy machine where wall time does not.
#pragma once

#include <map>
#include <string>

namespace fetchscope {

/// CPU seconds the calling thread has run (CLOCK_THREAD_CPUTIME_ID): user and system.
double ThreadCpuSeconds();

/// CPU seconds of the whole process, every thread, user and system (getrusage RUSAGE_SELF),
/// plus those of its waited-for children (RUSAGE_CHILDREN: --worker-mode process).
double ProcessCpuSeconds();

/// Adds the thread CPU time since it was made (or last lapped) to a counter.
class CpuLap {
 public:
  CpuLap() : start_(ThreadCpuSeconds()) {}
  /// Adds the seconds since the last lap to *into and starts the next lap.
  void Into(double* into) {
    const double now = ThreadCpuSeconds();
    *into += now - start_;
    start_ = now;
  }

 private:
  double start_;
};

/// The stages of a recorded frame's CPU time, each summed over frames (seconds). A stage that
/// runs on a thread the account does not see (llvmpipe's rasteriser threads; a multi-threaded
/// encoder's pool) is not in it: record runs each encoder with one thread, and bench measures
/// with LP_NUM_THREADS=0 so that llvmpipe rasterises on the render thread.
struct CpuStages {
  double sim = 0;           ///< physics and policy (render thread, between frames)
  double scene = 0;         ///< mjv_updateScene and the overlay geoms (MuJoCo on the CPU)
  double gl = 0;            ///< mjr_render and the readback (on llvmpipe: the rasteriser too)
  double hud = 0;           ///< the HUD and tile labels drawn into the read-back frame
  double copy = 0;          ///< frame copies on the render thread (row flip, GIF copy)
  double render_other = 0;  ///< the rest of the render thread's time per frame
  /// a randomized look's once-per-episode work: its draw (DrawLook, or the stored look read
  /// back) and the renderer taking it (texture pixels made and uploaded); the per-frame edits of
  /// the scene's geoms, lights and cameras are in `scene`
  double look = 0;
  double convert = 0;       ///< RGB to YUV (swscale) and its input copy
  double encode = 0;        ///< the video encoders (sending frames, flushing, muxing)
  double sheet = 0;         ///< the contact sheet: tiles kept, composed, PNG written
  double trajectory = 0;    ///< the trajectory JSON
  double encode_other = 0;  ///< the rest of the encoder thread's time

  CpuStages& operator+=(const CpuStages& o);
  /// Everything but gl: what the node's CPU cores pay per frame when a GPU draws.
  double OutsideGl() const;
  /// Every stage, keys as above.
  std::map<std::string, double> Items() const;
};

}  // namespace fetchscope
