#include "render/rays.h"

#include <cmath>

#include "util/error.h"

namespace raysort {

namespace {
RsVec3 to_rs(const Vec3& v) { return rs_vec3(v[0], v[1], v[2]); }
}  // namespace

RsCamera make_camera(const Camera& cam, std::uint32_t width, std::uint32_t height) {
  if (width == 0 || height == 0) throw Error("resolution must be at least 1x1");
  RsVec3 pos = to_rs(cam.position);
  RsVec3 forward = rs_normalize(rs_sub(to_rs(cam.look_at), pos));
  RsVec3 right = rs_normalize(rs_cross(forward, to_rs(cam.up)));
  RsVec3 up = rs_cross(right, forward);
  RsCamera c{};
  c.pos[0] = pos.x, c.pos[1] = pos.y, c.pos[2] = pos.z;
  c.forward[0] = forward.x, c.forward[1] = forward.y, c.forward[2] = forward.z;
  c.right[0] = right.x, c.right[1] = right.y, c.right[2] = right.z;
  c.up[0] = up.x, c.up[1] = up.y, c.up[2] = up.z;
  // Host-only setup value: every device receives the same float.
  c.tan_half_fov_y = static_cast<float>(std::tan(cam.fov_y_deg * 0.5 * 3.14159265358979323846 / 180.0));
  c.aspect = static_cast<float>(width) / static_cast<float>(height);
  c.width = width;
  c.height = height;
  return c;
}

}  // namespace raysort
