#include "bvh/prepared_scene.h"

#include <chrono>

namespace raysort {

PreparedScene prepare_scene(const std::string& name_or_path, const SceneOptions& opts) {
  PreparedScene p;
  const auto t0 = std::chrono::steady_clock::now();
  p.scene = load_scene(name_or_path, opts);
  p.tris = p.scene.flatten();
  p.load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  p.bvh = build_bvh(p.tris);
  return p;
}

}  // namespace raysort
