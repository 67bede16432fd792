#pragma once
// Ray sort keys: every encoder of docs/design.md, "Encoders", on the device (cl/encode.cl) and on
// the host (a bit-exact twin running the same key code, cl/keys*.h). Layouts: docs/encoders.md.
//
//   encode/encoder.h          which encoders there are (made from the list, cl/encoders.h)
//   encode/encoder_params.h   their knobs, as data
//   encode/encoder_family.h   how a family makes its keys: the interface every family implements
//   encode/encode_scene.h     EncodeScene: the per-scene inputs of the keys
//   encode/<family>_family.h  a family's own inputs (cuts, tables, learned statistics)
//   encode/device_encoder.h   DeviceEncoder::enqueue(encoder, bits, rays, order, n, keys, values)
//   encode_on_host(encoder, bits, scene, rays)   the host twin, keys as uint64 (below)
//
// A key of b bits (1..64; the suite uses 16, 32, 64) is the top b bits of the encoder's 64-bit
// code. On the device, keys of up to 32 bits are uint32 words and wider keys uint64 words.
#include <cstdint>
#include <vector>

#include "encode/box_set_family.h"
#include "encode/cost_cut_family.h"
#include "encode/cut_tables.h"
#include "encode/device_encoder.h"
#include "encode/encode_scene.h"
#include "encode/encoder.h"
#include "encode/encoder_family.h"
#include "encode/encoder_params.h"
#include "encode/region_cut_family.h"
#include "encode/two_level_family.h"
// The key layouts shared with the kernels (cl/keys*.h).
#include "keys_cut.h"
#include "keys_ppc.h"
#include "keys_spatial.h"

namespace raysort {

// The key of one ray (host twin of the kernels; same source for the key arithmetic).
std::uint64_t encode_ray(Encoder e, unsigned bits, const EncodeScene& scene, const RsRay& ray);
// Keys of every ray (host threads), keys[i] of rays[i].
std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const EncodeScene& scene,
                                          const std::vector<RsRay>& rays);
std::vector<std::uint64_t> encode_on_host(Encoder e, unsigned bits, const Bvh& bvh, const Aabb& scene_box,
                                          const EncoderParams& params, const std::vector<RsRay>& rays);

}  // namespace raysort
