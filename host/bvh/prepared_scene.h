#pragma once
// A scene ready to trace: loaded (with a command's --resolution / --spp / --shadow-rays / --bounces applied once, by
// load_scene), flattened into one triangle list, and its BVH built. Every command, the matrix
// runner and the tests start here.
#include <string>

#include "bvh/bvh.h"
#include "scene/load.h"

namespace raysort {

struct PreparedScene {
  Scene scene;
  Scene::Flat tris;
  Bvh bvh;
  double load_ms = 0.0;  // load + flatten, wall clock (the BVH's build time is bvh.build_ms)
  // The frame its batches are generated at: the scene's camera and sampling after the overrides.
  FrameSize frame() const {
    return {scene.camera.width, scene.camera.height, scene.effects.samples_per_pixel,
            scene.effects.shadow_rays_per_bounce, scene.effects.max_bounces};
  }
};

PreparedScene prepare_scene(const std::string& name_or_path, const SceneOptions& opts = {});

}  // namespace raysort
