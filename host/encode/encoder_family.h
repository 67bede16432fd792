#pragma once
// An encoder family: everything that differs between the ways a key is made, behind one interface
// (issue 41). The encoder list (cl/encoders.h) names each encoder's family; the family says
//   - its key-length rule (key_bits_problem),
//   - the scene inputs it builds (cuts, tables; kept per encoder in the EncodeScene) and uploads
//     (upload: the kernel's leading arguments),
//   - how its kernel is bound and launched (enqueue; the default fits most families),
//   - its host key, the bit-exact twin of the kernel (host_key),
//   - what it learns from an earlier batch or frame (learns_from, study, use).
// The table, DeviceEncoder, the host twin, the runner and encodebench call these and nothing
// encoder-specific. A new family is host/encode/<family>_family.cpp (defining
// encoder_family_<family>()) and its kernel header; docs/encoders.md, "Adding an encoder".
#include <CL/opencl.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "encode/encoder.h"
#include "encode/encoder_params.h"
#include "render/rays.h"
#include "runtime/runtime.h"

namespace raysort {

class EncodeScene;

// One argument of an encode kernel: a buffer, a count, or the scene frame by value.
using KernelArg = std::variant<cl::Buffer, cl_uint, RsEncodeFrame>;

// The kernels of one encode (most are one kernel; HCC_DIR with d > 1 and the spatial kernels'
// remainder launch two): the first's start to the last's end is its time.
struct EncodeEvents {
  cl::Event first, last;
  void wait() const;
  double ms() const;  // first kernel's start to last kernel's end (profiling)
};

// Uploads a family's inputs for one encoder and key length: named "<encoder> <bits>-bit <what>"
// (the names RAYSORT_TEST_MAX_ALLOC_BYTES matches), or once per scene (shared by every key length).
class DeviceUploads {
 public:
  DeviceUploads(Runtime& rt, std::string prefix, std::map<std::string, cl::Buffer>& per_scene)
      : rt_(rt), prefix_(std::move(prefix)), per_scene_(per_scene) {}
  template <class T, class Alloc>
  cl::Buffer buffer(const std::string& what, const std::vector<T, Alloc>& data) {
    return rt_.upload(prefix_ + what, data);
  }
  template <class T, class Alloc>
  cl::Buffer scene_buffer(const std::string& what, const std::vector<T, Alloc>& data) {
    auto it = per_scene_.find(what);
    if (it == per_scene_.end()) it = per_scene_.emplace(what, rt_.upload(what, data)).first;
    return it->second;
  }

 private:
  Runtime& rt_;
  std::string prefix_;
  std::map<std::string, cl::Buffer>& per_scene_;
};

// One encode as DeviceEncoder hands it to a family: keys[i], values[i] = i for rays[order[i]],
// i < count (count > 0), with the family's uploaded inputs.
struct EncodeLaunch {
  Encoder encoder;
  unsigned bits;
  const EncodeScene& scene;
  const std::vector<KernelArg>& inputs;  // what upload() returned
  const cl::Buffer& rays;
  const cl::Buffer& order;
  std::uint32_t count;
  const cl::Buffer& keys;
  const cl::Buffer& values;
  Runtime& rt;
  std::size_t local;                                          // work-group size
  std::function<cl::Kernel&(const std::string&)> kernel;      // by name, for this key width (_k32 / _k64)

  // Sets `leading` as the first arguments of k, then rays, order, count, bits, keys, values (the
  // signature of every family kernel but the spatial and nosort ones).
  void set_args(cl::Kernel& k, const std::vector<KernelArg>& leading) const;
  // Launches k over `items` work-items, padded to whole work-groups (the kernel guards on count).
  cl::Event launch(cl::Kernel& k, std::size_t items) const;
};

// The host key of one ray for one encoder and key length; safe to call from many threads (its
// inputs were built before it was returned).
using HostKey = std::function<std::uint64_t(const RsRay&)>;

// Where an encoder's learned input comes from (docs/encoders.md, "Beyond the paper"): nowhere, the
// batch traced just before this one in the same frame (hcc-traffic), or the same batch of a
// previous frame (hcc-region, mlhcc-cost). Never the batch being measured.
enum class LearnsFrom { Nothing, EarlierBatch, PreviousFrame };

// What a family learned for one batch; each family derives its own.
struct LearnedInput {
  virtual ~LearnedInput() = default;
};

class EncoderFamily {
 public:
  virtual ~EncoderFamily() = default;

  // "" when e takes keys of `bits` bits (1..64, checked before) with these knobs, else why not.
  virtual std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params) const;
  // The host key, with e's inputs for `bits` built (and cached in the scene) first.
  virtual HostKey host_key(Encoder e, unsigned bits, const EncodeScene& scene) const = 0;
  // Uploads e's inputs for `bits` and returns the kernel's leading arguments (EncodeLaunch::set_args).
  virtual std::vector<KernelArg> upload(Encoder e, unsigned bits, const EncodeScene& scene, DeviceUploads& up) const;
  // The kernels the family launches besides its encoders' own (the list's), without suffix.
  virtual std::vector<std::string> extra_kernels() const { return {}; }
  // Enqueues the encode. The default binds the encoder's kernel with set_args(inputs) and launches
  // one work-item per rays_per_work_item() rays.
  virtual EncodeEvents enqueue(const EncodeLaunch& launch) const;
  virtual unsigned rays_per_work_item() const { return 1; }

  // Whether host_key is the kernel's bit-exact twin. A family without one (encoders from files)
  // has its keys checked against themselves: the same keys on a second launch (bench/cell_measure.h).
  virtual bool has_host_twin() const { return true; }
  // The program holding e's kernels when it is not cl/encode.cl (built, or taken from rt's cache):
  // an encoder made at run time brings its own. Null: cl/encode.cl's kernels.
  virtual std::optional<cl::Program> own_program(Encoder, Runtime&) const { return std::nullopt; }

  virtual LearnsFrom learns_from(Encoder) const { return LearnsFrom::Nothing; }
  // What e learns from `before` (the batch learns_from names, traced before the one it encodes).
  virtual std::shared_ptr<const LearnedInput> study(Encoder e, const EncodeScene& scene, const RayBatch& before) const;
  // Makes `learned` e's input in `scene` (null: none; the keys then fall back as the family says).
  virtual void use(Encoder e, const LearnedInput* learned, EncodeScene& scene) const;
};

// One function per family of the list, each defined in host/encode/<family>_family.cpp.
#define RS_DECLARE_FAMILY(FAMILY) const EncoderFamily& encoder_family_##FAMILY();
RS_ENCODER_FAMILIES(RS_DECLARE_FAMILY)
#undef RS_DECLARE_FAMILY
// The family of the encoders from files (encode/encoder_file.h), outside the list: no kernel of
// cl/encode.cl, a program per file (host/encode/file_family.cpp).
const EncoderFamily& encoder_family_file();

// Builds the programs of the encoders that bring their own (own_program) before any work, so a file
// that does not compile is refused with its build log before a result set is written. Throws Error.
void build_own_programs(Runtime& rt, const std::vector<Encoder>& encoders);
// Whether e's keys have a host twin to be checked against (EncoderFamily::has_host_twin).
bool has_host_twin(Encoder e);

// "" when `bits` is a valid key length for e with these parameters (1..64, then the family's rule:
// MLHCC: even; HCC_DIR: more than d bits; hcc-region: more than r bits and r ≤ 8; hcc-traffic:
// 0 ≤ β ≤ 1; mlhcc-cost: even, at least 4, and fewer cost bits than half the key), else why not.
std::string key_bits_problem(Encoder e, unsigned bits, const EncoderParams& params);
// Throws Error with key_bits_problem's text.
void check_key_bits(Encoder e, unsigned bits, const EncoderParams& params);

}  // namespace raysort
