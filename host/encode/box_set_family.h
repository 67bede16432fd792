#pragma once
// The box-set family (Xiang et al. §4.2 and §5, appendix A; issue 21): one key bit per box the ray
// segment overlaps (cl/keys_cut.h, rs_box_set_code). Its encoders differ in their boxes: HCC's cut
// nodes by descending HAD, RegularGrid's cells, HCC_DIR's b − d cut nodes followed by d direction
// bits, and hcc-traffic's cut by HAD blended with the traffic of the batch traced before.
#include <cstdint>
#include <vector>

#include "encode/encode_scene.h"
#include "encode/encoder_family.h"
#include "keys_cut.h"

namespace raysort {

// The boxes of a box-set encoder for keys of `bits` bits, in bit order, cached.
const std::vector<RsBox>& box_set(const EncodeScene& scene, Encoder e, unsigned bits);
// The same boxes as rs_box_set_code reads them: sixteen-box groups (rs_cut_groups) and their
// number, cached.
struct CutSet {
  std::vector<RsCutGroup> groups;
  rs_u32 box_count = 0;
};
const CutSet& cut_set(const EncodeScene& scene, Encoder e, unsigned bits);

// hcc-traffic's input: node visit counts of an earlier batch (trace/tracer.h, node_traffic; indexed
// like bvh.nodes). Empty (the default, and the first batch of a frame): no traffic, the cut is
// HCC's. Setting it drops hcc-traffic's cached cuts; the other encoders' inputs stay.
void set_node_traffic(EncodeScene& scene, std::vector<std::uint64_t> visits);
// hcc-traffic's cut of `size` nodes: priority_cut by traffic_priority(HAD, traffic, β), ties by
// HAD, then node index. Cached until the traffic changes.
const std::vector<std::uint32_t>& traffic_cut(const EncodeScene& scene, unsigned size);

// What hcc-traffic learns from the batch before (LearnsFrom::EarlierBatch): its node traffic.
struct NodeTraffic : LearnedInput {
  std::vector<std::uint64_t> visits;
};

}  // namespace raysort
