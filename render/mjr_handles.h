// RAII owners for MuJoCo's visualisation handles (mjvScene, mjrContext). mjvCamera and
// mjvOption own no memory and are used as plain values.
#pragma once

#include <mujoco/mujoco.h>

#include <utility>

namespace fetchscope {

/// Owns an mjvScene (mjv_makeScene / mjv_freeScene).
class MjvScene {
 public:
  /// Allocates room for `maxgeom` geoms of `model`.
  MjvScene(const mjModel* model, int maxgeom) {
    mjv_defaultScene(&scene_);
    mjv_makeScene(model, &scene_, maxgeom);
    owned_ = true;
  }
  ~MjvScene() { Free(); }
  MjvScene(const MjvScene&) = delete;
  MjvScene& operator=(const MjvScene&) = delete;
  MjvScene(MjvScene&& other) noexcept : scene_(other.scene_), owned_(other.owned_) {
    other.owned_ = false;
  }
  MjvScene& operator=(MjvScene&& other) noexcept {
    if (this != &other) {
      Free();
      scene_ = other.scene_;
      owned_ = std::exchange(other.owned_, false);
    }
    return *this;
  }

  mjvScene* get() { return &scene_; }              ///< the scene
  const mjvScene* get() const { return &scene_; }  ///< the scene

 private:
  void Free() noexcept {
    if (owned_) mjv_freeScene(&scene_);
    owned_ = false;
  }

  mjvScene scene_;
  bool owned_ = false;
};

/// Owns an mjrContext (mjr_makeContext / mjr_freeContext). Its GL context must be current
/// on the calling thread when it is made and when it is destroyed.
class MjrContext {
 public:
  /// Uploads `model`'s textures, meshes and fonts and makes the offscreen buffer of
  /// model->vis.global.offwidth x offheight.
  MjrContext(const mjModel* model, int fontscale) {
    mjr_defaultContext(&context_);
    mjr_makeContext(model, &context_, fontscale);
    owned_ = true;
  }
  ~MjrContext() { Free(); }
  MjrContext(const MjrContext&) = delete;
  MjrContext& operator=(const MjrContext&) = delete;
  MjrContext(MjrContext&& other) noexcept : context_(other.context_), owned_(other.owned_) {
    other.owned_ = false;
  }
  MjrContext& operator=(MjrContext&& other) noexcept {
    if (this != &other) {
      Free();
      context_ = other.context_;
      owned_ = std::exchange(other.owned_, false);
    }
    return *this;
  }

  mjrContext* get() { return &context_; }              ///< the context
  const mjrContext* get() const { return &context_; }  ///< the context

 private:
  void Free() noexcept {
    if (owned_) mjr_freeContext(&context_);
    owned_ = false;
  }

  mjrContext context_;
  bool owned_ = false;
};

}  // namespace fetchscope
