// The family of the encoders from files (encode/encoder_file.h; cl/encode_file.h): the user's
// rs_file_code inside a kernel built at run time, given the scene frame, HCC's cut of the key's
// length and the binary BVH. It has no host twin: its keys are checked against themselves.
#include <fmt/format.h>

#include "encode/box_set_family.h"
#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "encode/encoder_file.h"
#include "util/error.h"

namespace raysort {

namespace {

const EncoderFile& file_of(Encoder e) {
  const EncoderFile* f = encoder_file(e);
  if (!f) throw Error(fmt::format("{} is not an encoder from a file", encoder_name(e)));
  return *f;
}

class FileFamily final : public EncoderFamily {
 public:
  bool has_host_twin() const override { return false; }

  HostKey host_key(Encoder e, unsigned, const EncodeScene&) const override {
    throw Error(fmt::format("{} (from {}) has no host twin: its keys exist only on an OpenCL device", encoder_name(e),
                            file_of(e).path));
  }

  // The leading arguments of encode_file_k32 / _k64 (cl/encode_file.h): the frame, HCC's cut of
  // `bits` nodes (HCC's own inputs, cached in the scene), the binary BVH and its triangles (once per
  // scene).
  std::vector<KernelArg> upload(Encoder, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const override {
    const CutSet& cut = cut_set(scene, Encoder::HCC, bits);
    const Bvh& bvh = scene.bvh();
    return {scene.frame(),
            up.buffer("cut boxes", cut.groups),
            cut.box_count,
            up.scene_buffer("bvh nodes (encoders from files)", bvh.nodes),
            static_cast<cl_uint>(bvh.nodes.size()),
            up.scene_buffer("triangles (encoders from files)", bvh.triangles)};
  }

  // The file inside cl/encode_file.h's kernels, built once per device (the runtime caches it). A
  // build error is the user's: the log, which names the file's own lines (#line), and the fix.
  std::optional<cl::Program> own_program(Encoder e, Runtime& rt) const override {
    const EncoderFile& file = file_of(e);
    try {
      return rt.build_source(encoder_file_program(file), "encoder file " + file.path);
    } catch (const BuildError& b) {
      throw Error(fmt::format("encoder file {} ({}) does not compile on {} ({}); fix it at the lines of the OpenCL "
                              "build log below (docs/encoders.md, \"An encoder from a file\"):\n{}",
                              file.path, file.name, rt.info().name, rt.info().platform_name, b.log()));
    }
  }
};

}  // namespace

const EncoderFamily& encoder_family_file() {
  static const FileFamily family;
  return family;
}

}  // namespace raysort
